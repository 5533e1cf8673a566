"""The domain of a case: the rectangle of ``[geometry]``, or a user's mesh.

A rectangle ``[0, width] x [0, height]`` has four edges (left, right, bottom, top) and
takes its nodes from ``[discretisation]`` (:mod:`soilwater.case.grid`). A mesh
(``geometry.mesh``, :mod:`soilwater.geometry.mesh`) brings its own nodes and triangles,
and its boundary groups (physical curves) take the place of the edges.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.case.boundary import EDGES
from soilwater.case.entries import check_keys, number, string
from soilwater.case.schema import KEYS, LENGTHS
from soilwater.errors import require
from soilwater.geometry.mesh import Mesh, read_mesh

#: Shapes of ``geometry.shape``.
SHAPES = ("rectangle", "mesh")


@dataclass(frozen=True)
class Geometry:
    """The rectangle ``[0, width] x [0, height]`` [m], or a :class:`Mesh` (``shape =
    "mesh"``), whose bounding box from the origin gives ``width`` and ``height``."""

    width: float
    height: float
    shape: str = "rectangle"
    mesh: Mesh | None = None

    @property
    def edges(self):
        """Names of the boundary's parts: :data:`~soilwater.case.boundary.EDGES`, or the
        mesh's boundary groups."""
        return EDGES if self.mesh is None else self.mesh.groups

    def edge_of(self, a, b):
        """Index into :attr:`edges` of the boundary facets from ``a`` to ``b`` (P, 2) [m],
        initial positions: the rectangle's edge nearest to the midpoint, or the mesh
        facet's group."""
        if self.mesh is not None:
            return self.mesh.facet_group(a, b)
        mid = (np.asarray(a, float) + b) / 2
        dist = np.stack([np.abs(mid[:, 0]), np.abs(mid[:, 0] - self.width),
                         np.abs(mid[:, 1]), np.abs(mid[:, 1] - self.height)], axis=1)
        return np.argmin(dist, axis=1)

    def region_of(self, points):
        """(P,) int: each point's material region (index into the mesh's regions; 0 on
        a rectangle)."""
        if self.mesh is None:
            return np.zeros(len(np.atleast_2d(points)), int)
        return self.mesh.region_of(points)

    def inside(self, points, tol=0.0):
        """(P,) bool: points [m] in the closed domain, within ``tol`` [m]."""
        points = np.atleast_2d(np.asarray(points, float))
        if self.mesh is not None:
            return self.mesh.inside(points, tol)
        return np.all((points >= -tol) & (points <= np.array([self.width, self.height]) + tol),
                      axis=1)

    def to_dict(self):
        """The ``[geometry]`` table."""
        if self.mesh is not None:
            return {"shape": "mesh", "mesh": self.mesh.path}
        return {"shape": self.shape, "width": self.width, "height": self.height}


def read_geometry(table):
    """The :class:`Geometry` of a ``[geometry]`` table: ``width`` and ``height``, or
    ``mesh`` (a ``.msh`` or ``.geo`` path)."""
    check_keys(table, KEYS["geometry"], "geometry")
    shape = string(table, "shape", "geometry", "mesh" if "mesh" in table else "rectangle",
                   SHAPES)
    if shape == "mesh":
        require("mesh" in table and not {"width", "height"} & set(table), "geometry: a "
                "mesh takes geometry.mesh = \"file.msh\" (or .geo), and its size from the "
                "mesh: give mesh and no width or height")
        mesh = read_mesh(string(table, "mesh", "geometry", None))
        return Geometry(*mesh.size, shape="mesh", mesh=mesh)
    require("mesh" not in table, "geometry.mesh needs geometry.shape = \"mesh\" (the "
            "default when mesh is given): remove shape")
    width, height = number(table, "width", "geometry"), number(table, "height", "geometry")
    for key, value in (("width", width), ("height", height)):
        require(LENGTHS[0] <= value <= LENGTHS[1], f"geometry.{key} = {value:g} must lie "
                f"in [{LENGTHS[0]:g}, {LENGTHS[1]:g}] m: give the size of the rectangle in m")
    return Geometry(width=width, height=height)
