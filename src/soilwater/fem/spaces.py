"""Meshes, element pairs and boundary DOF sets of the FEM reference (scikit-fem).

The mesh vertices are the case's nodes (:meth:`soilwater.case.model.Case.nodes`, same order), so
a FEM run and an EFG run of a case share their node set; second-order elements add
scikit-fem's midside (and, for Q2, centre) DOFs. Triangles: two per grid cell for the
``grid`` layout (diagonal from lower left to upper right), Delaunay triangles
(scipy.spatial) for ``grid+centres`` (four per cell around its centre), a mesh's own
triangles (``geometry.mesh``). Quadrilaterals: the cells of the structured grid (``grid``
layout only).

Every element pair uses one Gauss rule for all terms, so the material points (quadrature
points) of the displacement and the pressure bases coincide; they keep their place in the
reference element while the mesh moves, which carries the material state from step to
step without remapping. A triangle mesh can be replaced by new triangles on the same
vertices (:meth:`Space.remeshed`, the re-meshing of :mod:`soilwater.fem.solver`).
"""

from dataclasses import dataclass

import numpy as np
from scipy.spatial import Delaunay
from skfem import (CellBasis, ElementQuad1, ElementQuad2, ElementTriP1, ElementTriP2,
                   FacetBasis, MeshQuad, MeshTri)

from soilwater.errors import InputError


@dataclass(frozen=True)
class Pair:
    """An element pair: cell shape, displacement and pressure elements, Gauss order.

    ``stabilised`` adds the flow-equation perturbation of Aguilar et al. (2008) to the
    continuity equation (see :mod:`soilwater.fem.solver`). ``smoother`` is the Krylov
    back-end's AMG smoother for the pair and ``iterative`` whether that back-end suits
    it (inf-sup stable or stabilised), so that it is the default on large systems
    (:class:`soilwater.linalg.layout.Layout`). ``single``: PARDISO factorises its tangents in single
    precision (:attr:`soilwater.linalg.layout.Layout.single`), where measured to pay
    (``python docs/experiments/direct_single.py``): fem-th (one bench step's solve at 10^5
    nodes 31.3 s against 44.8 s); not fem-p1p1-stab (6.6 s against 6.4 s, and 65 of the
    199 factorisations of its unconfined compression were redone in double); fem-q2q1
    not measured.
    """

    shape: str
    u_element: type
    p_element: type
    intorder: int
    stabilised: bool = False
    smoother: str = "gauss_seidel"
    iterative: bool = False
    single: bool = False


#: The FEM methods of ``soilwater run --method``.
PAIRS = {
    "fem-th": Pair("triangle", ElementTriP2, ElementTriP1, 4, smoother="schwarz",
                   iterative=True, single=True),
    "fem-p1p1": Pair("triangle", ElementTriP1, ElementTriP1, 2),
    "fem-p1p1-stab": Pair("triangle", ElementTriP1, ElementTriP1, 2, stabilised=True,
                          iterative=True),
    "fem-q1q1": Pair("quad", ElementQuad1, ElementQuad1, 3),
    "fem-q2q1": Pair("quad", ElementQuad2, ElementQuad1, 5, iterative=True),
}


def initial_mesh(case, method):
    """The mesh of the case's initial nodes for a method's cell shape.

    Raises
    ------
    InputError
        A quadrilateral method on a ``grid+centres`` case or a mesh.
    """
    pair = PAIRS[method]
    nodes = case.nodes()
    d = case.discretisation
    if case.geometry.mesh is not None:
        if pair.shape == "quad":
            raise InputError(f"--method {method} needs a structured grid (quadrilaterals), "
                             f"case {case.name!r} is a triangle mesh (geometry.mesh): use "
                             "fem-th, fem-p1p1 or fem-p1p1-stab")
        return MeshTri(np.ascontiguousarray(nodes.T),
                       np.ascontiguousarray(case.geometry.mesh.triangles.T))
    k = (np.arange(d.ny - 1)[:, None] * d.nx + np.arange(d.nx - 1)[None, :]).ravel()
    if pair.shape == "quad":
        if d.layout != "grid":
            raise InputError(f"--method {method} needs discretisation.layout = 'grid' "
                             f"(quadrilaterals on the grid), case {case.name!r} has "
                             f"{d.layout!r}: use fem-th, fem-p1p1 or fem-p1p1-stab")
        return MeshQuad(np.ascontiguousarray(nodes.T),
                        np.ascontiguousarray([k, k + 1, k + 1 + d.nx, k + d.nx]))
    if d.layout == "grid":
        t = np.hstack([[k, k + 1, k + 1 + d.nx], [k, k + 1 + d.nx, k + d.nx]])
    else:
        t = Delaunay(nodes).simplices.T
    return MeshTri(np.ascontiguousarray(nodes.T), np.ascontiguousarray(t))


@dataclass
class Space:
    """Topology, elements and boundary DOF sets of a mesh on the case's nodes.

    Attributes
    ----------
    mesh0 : skfem.Mesh
        The mesh's elements on the initial positions of its vertices (the case nodes): the
        initial mesh, or the elements of a re-meshing, which may be tangled there (only
        their topology and the initial positions of boundary facets are used).
    pair : Pair
    edge_facets : dict
        Boundary facet indices of each edge name (left, right, bottom, top, or a mesh's
        boundary groups).
    u_dofs, p_dofs : dict
        Scalar DOF indices of the displacement / pressure basis on each edge (vertex and
        midside DOFs), from the initial coordinates.
    n_u, n_p : int
        DOFs of one displacement component and of the pressure.
    corners : ndarray of int, shape (E, 3 or 4)
        Vertex indices of every element, counter-clockwise where the elements were made
        (the initial mesh, or the configuration of the re-meshing): scikit-fem sorts each
        triangle's indices, which leaves half the grid's triangles clockwise;
        ``vertices[corners]`` are the cells of :func:`soilwater.geometry.quality.cell_quality`.
    doflocs0 : tuple of ndarray
        Initial positions (2, n_u) and (2, n_p) [m] of the displacement and pressure
        DOFs, where the boundary kinds are read (:meth:`soilwater.case.model.Case.edge_conditions`).
    """

    mesh0: object
    pair: Pair
    edge_facets: dict
    u_dofs: dict
    p_dofs: dict
    n_u: int
    n_p: int
    corners: np.ndarray
    doflocs0: tuple

    @classmethod
    def build(cls, case, method):
        """The space of the initial mesh (:func:`initial_mesh`)."""
        mesh = initial_mesh(case, method)
        ub, pb = cell_bases(mesh, PAIRS[method])
        return cls._of(case, mesh, PAIRS[method], ub, pb, _counter_clockwise(mesh),
                       (ub.doflocs, pb.doflocs))

    def remeshed(self, case, vertices, triangles):
        """The space of new triangles on the same vertices.

        Parameters
        ----------
        case : Case
        vertices : ndarray, shape (N, 2)
            Current vertex positions [m].
        triangles : ndarray of int, shape (E, 3)
            Vertex indices, counter-clockwise on ``vertices``, tiling the current
            boundary polygon (:func:`soilwater.geometry.triangulation.conforms`).

        Returns
        -------
        Space
            scikit-fem's DOF numbering of the new elements (bases on the current
            vertices, where the elements are valid); initial DOF positions are those of
            the function linear along every edge that takes the initial vertex positions
            (:func:`vertex_interpolant`): a boundary DOF keeps its position, so its kind.
        """
        mesh0 = MeshTri(np.ascontiguousarray(self.mesh0.p),
                        np.ascontiguousarray(triangles.T))
        ub, pb = cell_bases(type(mesh0)(np.ascontiguousarray(vertices.T), mesh0.t,
                                        sort_t=False), self.pair)
        doflocs0 = tuple(vertex_interpolant(b, mesh0.facets, mesh0.p.T).T for b in (ub, pb))
        return self._of(case, mesh0, self.pair, ub, pb, triangles, doflocs0)

    @classmethod
    def _of(cls, case, mesh0, pair, ub, pb, corners, doflocs0):
        edge_facets = _edge_facets(mesh0, case.geometry)
        return cls(mesh0, pair, edge_facets,
                   {e: ub.get_dofs(f).flatten() for e, f in edge_facets.items()},
                   {e: pb.get_dofs(f).flatten() for e, f in edge_facets.items()},
                   ub.N, pb.N, corners, doflocs0)

    def moved(self, vertices):
        """The mesh with the same topology on vertices (N, 2) [m]."""
        return type(self.mesh0)(np.ascontiguousarray(vertices.T), self.mesh0.t,
                                sort_t=False)

    def facet_basis(self, mesh, edge):
        """Displacement basis on the current facets of one edge (for tractions)."""
        return FacetBasis(mesh, self.pair.u_element(), facets=self.edge_facets[edge],
                          intorder=self.pair.intorder)

    @property
    def cell_type(self):
        """VTK cell name of the vertex mesh."""
        return "quad" if self.pair.shape == "quad" else "triangle"


def cell_bases(mesh, pair):
    """Scalar displacement and pressure bases on one mesh, with one Gauss rule."""
    return (CellBasis(mesh, pair.u_element(), intorder=pair.intorder),
            CellBasis(mesh, pair.p_element(), intorder=pair.intorder))


def vertex_interpolant(basis, facets, values):
    """DOF values of the function that is linear along every edge and takes ``values``
    (N, k) at the vertices, for a basis whose DOFs are the vertices and edge midpoints
    (P1, P2): vertex DOFs take the vertex values, midside DOFs the mean of their edge's
    two ends. Returns (n, k).

    ``facets`` (2, F) are the mesh's edges (``mesh.facets``), in the basis' numbering.

    Examples
    --------
    >>> mesh = MeshTri()
    >>> basis = CellBasis(mesh, ElementTriP2())
    >>> np.allclose(vertex_interpolant(basis, mesh.facets, mesh.p.T), basis.doflocs.T)
    True
    """
    values = np.asarray(values, float)
    out = np.empty((basis.N, values.shape[1]))
    out[basis.nodal_dofs[0]] = values
    if basis.facet_dofs.size:
        out[basis.facet_dofs[0]] = values[facets].mean(axis=0)
    return out


def _counter_clockwise(mesh):
    """Vertex indices (E, 3 or 4) of the mesh's elements, counter-clockwise on its
    vertices."""
    t = mesh.t.T.copy()
    p = mesh.p.T[t]
    a, b = p[:, 1] - p[:, 0], p[:, -1] - p[:, 0]
    clockwise = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0] < 0
    t[clockwise] = t[clockwise, ::-1]
    return t


def _edge_facets(mesh, geometry):
    """Boundary facets of each edge of the domain
    (:meth:`soilwater.case.domain.Geometry.edge_of`, initial positions)."""
    facets = mesh.boundary_facets()
    a, b = (mesh.p[:, mesh.facets[k, facets]].T for k in range(2))
    edge = geometry.edge_of(a, b)
    return {name: facets[edge == k] for k, name in enumerate(geometry.edges)}
