"""A user's domain as a triangle mesh: read with meshio (a ``.msh`` file) or meshed by gmsh
(a ``.geo`` file, with the optional ``gmsh`` package).

The mesh's named physical groups are the case's vocabulary: physical curves on the
boundary become the boundary groups of ``[boundary.NAME]``, physical surfaces the material
regions. Both methods read one :class:`Mesh`: EFG takes its vertices as nodes and its
triangles as initial cells, each FEM triangle pair builds its elements on them (P2
mid-sides added by scikit-fem).

Conventions: coordinates [m] in the x-y plane, y up, the bounding box's lower-left corner
at the origin (as for the rectangle); one boundary loop (no holes); every boundary facet
in exactly one physical curve, every triangle in at most one physical surface. Physical
curves inside the domain (between regions) are allowed and carry no boundary condition.
"""

import os
import tempfile
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from soilwater.errors import InputError, require

#: File suffixes :func:`read_mesh` takes: a mesh, or a gmsh geometry it meshes.
SUFFIXES = (".msh", ".geo")


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh of a simply connected 2-D domain with named groups.

    Attributes
    ----------
    path : str
        The file it was read from (absolute).
    points : ndarray, shape (N, 2)
        Vertex coordinates [m], only those of triangles.
    triangles : ndarray of int, shape (T, 3)
        Vertex indices, counter-clockwise.
    region : ndarray of int, shape (T,)
        Index into :attr:`regions` of each triangle.
    regions : tuple of str
        Names of the physical surfaces.
    loop : ndarray of int, shape (F,)
        The boundary vertices, counter-clockwise, each once: facet k runs from
        ``loop[k]`` to ``loop[k + 1]`` (cyclically).
    group : ndarray of int, shape (F,)
        Index into :attr:`groups` of each boundary facet.
    groups : tuple of str
        Names of the physical curves on the boundary.
    interior : tuple of str
        Names of the physical curves inside the domain (on no boundary facet): known to
        the mesh, but no boundary group.
    """

    path: str
    points: np.ndarray
    triangles: np.ndarray
    region: np.ndarray
    regions: tuple
    loop: np.ndarray
    group: np.ndarray
    groups: tuple
    interior: tuple

    def __eq__(self, other):
        return isinstance(other, Mesh) and self.digest == other.digest

    def __hash__(self):
        return hash(self.digest)

    @cached_property
    def digest(self):
        """sha256 of the mesh's content (vertices, triangles, groups and regions): what a
        cached run on it depends on, and what makes two meshes equal; not the file's
        name."""
        import hashlib

        digest = hashlib.sha256()
        for array in (self.points, self.triangles, self.region, self.loop, self.group):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(repr((self.regions, self.groups)).encode())
        return digest.hexdigest()

    @property
    def size(self):
        """``(width, height)`` [m]: the bounding box from the origin."""
        return tuple(float(v) for v in self.points.max(axis=0))

    @property
    def spacing(self):
        """The shortest triangle edge [m]."""
        edges = self.points[self.triangles] - self.points[np.roll(self.triangles, -1, 1)]
        return float(np.hypot(edges[..., 0], edges[..., 1]).min())

    def surface(self):
        """(F,) bool: the boundary facets that face up (outward normal with a positive y
        component: the loop runs counter-clockwise, so right to left along them)."""
        d = self.points[np.roll(self.loop, -1)] - self.points[self.loop]
        return d[:, 0] < -1e-12 * max(self.size)

    def group_length(self, name):
        """Total initial length [m] of boundary group ``name``."""
        d = self.points[np.roll(self.loop, -1)] - self.points[self.loop]
        return float(np.hypot(d[:, 0], d[:, 1])[self.group == self.groups.index(name)].sum())

    def group_nodes(self, name):
        """Sorted indices into :attr:`points` of the vertices on boundary group ``name``."""
        on = self.group == self.groups.index(name)
        return np.unique(np.concatenate([self.loop[on], np.roll(self.loop, -1)[on]]))

    def facet_group(self, a, b):
        """Index into :attr:`groups` of the boundary facets from ``a`` to ``b`` (P, 2)
        [m] (initial positions, either direction), by the nearest facet midpoint."""
        from scipy.spatial import cKDTree

        ends = self.points[np.stack([self.loop, np.roll(self.loop, -1)])]
        _, nearest = cKDTree(ends.mean(axis=0)).query((np.asarray(a) + b) / 2)
        return self.group[nearest]

    def region_of(self, points):
        """(P,) int: index into :attr:`regions` of the triangle that holds each point
        [m] (initial positions); a point on no triangle (on the boundary, to round-off)
        takes the triangle with the nearest centroid."""
        from scipy.spatial import cKDTree

        points = np.atleast_2d(np.asarray(points, float))
        cell = np.asarray(_finder(self)(points[:, 0], points[:, 1]))
        lost = cell < 0
        if lost.any():
            centroids = self.points[self.triangles].mean(axis=1)
            cell[lost] = cKDTree(centroids).query(points[lost])[1]
        return self.region[cell]

    def layers(self):
        """The regions met going down the vertical through the middle of the bounding
        box: ``(top, bottom, region)`` [m] from the top, one per run of a region."""
        y = np.unique(self.points[:, 1])
        mid = (y[1:] + y[:-1]) / 2
        region = self.region_of(np.column_stack([np.full(len(mid), self.size[0] / 2),
                                                 mid]))
        change = np.flatnonzero(np.diff(region)) + 1
        starts, ends = np.r_[0, change], np.r_[change, len(mid)]
        return [(float(y[e]), float(y[s]), int(region[s])) for s, e in
                zip(starts, ends)][::-1]

    def inside(self, points, tol=0.0):
        """(P,) bool: points [m] in the domain (closed; within ``tol`` [m] of it)."""
        from matplotlib.path import Path as Polygon

        return Polygon(self.points[self.loop]).contains_points(points, radius=tol) | \
            Polygon(self.points[self.loop[::-1]]).contains_points(points, radius=tol)


@lru_cache(maxsize=8)
def _finder(mesh):
    """matplotlib's triangle finder of ``mesh``, built once per mesh (the initial state
    asks for regions at every step's boundary points)."""
    from matplotlib.tri import Triangulation

    return Triangulation(*mesh.points.T, mesh.triangles).get_trifinder()


def read_mesh(path, where="geometry.mesh"):
    """The :class:`Mesh` of a ``.msh`` file (meshio) or of a ``.geo`` file (meshed by
    gmsh, in 2-D, with its own settings).

    Parameters
    ----------
    path : str or Path
    where : str
        The case key that gave the path, for the error messages.

    Raises
    ------
    InputError
        One line naming ``where`` and the fix: a missing path, one that is no regular
        file (a folder, a pipe, a device), an empty file, a ``.msh`` that is not a gmsh
        mesh, a ``.geo`` without the gmsh package or that gmsh cannot mesh, a non-finite
        vertex coordinate, elements other than triangles, a triangle in two physical
        surfaces, a domain off the origin or with holes, a boundary facet in no physical
        curve, no physical curve at all.
    """
    import meshio

    path = Path(path)
    name = f"{where} = {str(path)!r}"
    require(path.exists(), f"{name} does not exist (a relative path is read from the case "
            "file's folder)")
    kind = "a folder" if path.is_dir() else "a device, pipe or socket"
    require(path.is_file(), f"{name} is {kind}, not a regular file: give the path of a "
            "gmsh mesh (.msh) or geometry (.geo) file")
    require(path.suffix in SUFFIXES, f"{name}: give a gmsh mesh (.msh) or geometry (.geo)")
    require(path.stat().st_size > 0, f"{name} is empty (0 bytes): give a mesh written by "
            "gmsh (gmsh -2 -format msh4) or a gmsh geometry (.geo)")
    if path.suffix == ".geo":
        raw = _gmsh(path, where)
    else:
        try:
            raw = meshio.gmsh.read(path)
        except (meshio.ReadError, ValueError, KeyError, IndexError) as err:
            raise InputError(f"{name} is not a gmsh mesh{f' ({err})' if str(err) else ''}"
                             ": write it with gmsh (-format msh4 or msh2)") from None
    return _mesh(raw, str(path.resolve()), where)


def _gmsh(path, where):
    """meshio's mesh of the 2-D mesh gmsh makes of the geometry file ``path``."""
    import meshio

    try:
        import gmsh
    except ImportError:
        raise InputError(f"{where} = {str(path)!r} needs the gmsh package to mesh it: "
                         "pip install 'soilwater[geometry]', or mesh it yourself "
                         f"(gmsh -2 {path.name}) and give the .msh") from None
    fd, target = tempfile.mkstemp(suffix=".msh")
    os.close(fd)
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        gmsh.model.mesh.generate(2)
        gmsh.write(target)
        return meshio.read(target, file_format="gmsh")
    except Exception as err:  # gmsh raises plain Exception with its own message
        raise InputError(f"{where} = {str(path)!r}: gmsh could not mesh it ({err}): correct "
                         f"the geometry (gmsh {path.name} shows it)") from None
    finally:
        gmsh.finalize()
        os.unlink(target)


def _mesh(raw, path, where):
    """The :class:`Mesh` of a meshio mesh read from gmsh's format."""
    kinds = {block.type for block in raw.cells} - {"vertex", "line", "triangle"}
    require(not kinds, f"{where}: the mesh holds {', '.join(sorted(kinds))} elements: "
            "soilwater takes 3-node triangles (and 2-node lines on the boundary): mesh "
            "with Mesh.ElementOrder = 1 and without recombination")
    bad = np.flatnonzero(~np.isfinite(raw.points).all(axis=1))
    if len(bad):
        raise InputError(f"{where}: {len(bad)} vertex(es) have a non-finite coordinate (NaN "
                         f"or infinite), the first node {bad[0] + 1} in the file's order: "
                         "remesh the geometry with gmsh")
    require(np.allclose(raw.points[:, 2:], 0.0), f"{where}: the mesh is not in the x-y "
            "plane (z != 0): give a 2-D mesh")
    names = {int(tag): name for name, (tag, dim) in raw.field_data.items()}
    dims = {int(tag): int(dim) for _, (tag, dim) in raw.field_data.items()}
    tags = raw.cell_data.get("gmsh:physical", [np.zeros(len(b.data), int)
                                               for b in raw.cells])
    require(any(b.type == "triangle" for b in raw.cells), f"{where}: the mesh has no "
            "triangles: mesh the surfaces (gmsh -2)")
    triangles, surface = _cells(raw, tags, names, where)
    used, triangles = np.unique(triangles, return_inverse=True)
    triangles = triangles.reshape(-1, 3)
    points = raw.points[used, :2].astype(float)
    low, scale = points.min(axis=0), np.ptp(points, axis=0).max()
    tol = 1e-9 * scale
    require(np.all(np.abs(low) <= tol), f"{where}: the domain's lower-left corner is at "
            f"({low[0]:g}, {low[1]:g}), not at the origin: translate the geometry by "
            f"({-low[0]:g}, {-low[1]:g}) (gmsh: Translate {{{-low[0]:g}, {-low[1]:g}, 0}} "
            "{ Surface{:}; })")
    d = points[triangles[:, 1:]] - points[triangles[:, :1]]
    area = d[:, 0, 0] * d[:, 1, 1] - d[:, 0, 1] * d[:, 1, 0]
    require(np.all(np.abs(area) > 1e-12 * scale**2), f"{where}: the mesh has "
            "degenerate triangles (zero area): remesh it")
    triangles[area < 0] = triangles[area < 0][:, [0, 2, 1]]
    loop = _loop(triangles, points, where)
    surfaces, region = np.unique(surface, return_inverse=True)
    regions = tuple(names.get(int(t), "domain") for t in surfaces)
    group, groups, interior = _groups(raw, tags, names, dims, used, loop, points, where)
    return Mesh(path, points, triangles, region, regions, loop, group, groups, interior)


def _cells(raw, tags, names, where):
    """Each triangle of ``raw`` once, in file order, and the tag of its physical surface.

    A triangle in several physical surfaces is listed once per surface in the msh2
    format, and once with its entity's first surface in msh4 (the others then hold its
    block in ``raw.cell_sets``): either way it is refused.

    Returns
    -------
    triangles : ndarray of int, shape (T, 3)
    surface : ndarray of int, shape (T,)
    """
    blocks = [k for k, b in enumerate(raw.cells) if b.type == "triangle"]
    surfaces = {name: tag for name, (tag, dim) in raw.field_data.items() if dim == 2}
    pairs = [(raw.cells[k].data, tags[k]) for k in blocks]
    pairs += [(raw.cells[k].data[raw.cell_sets[name][k]],
               np.full(len(raw.cell_sets[name][k]), tag))
              for name, tag in surfaces.items() if name in raw.cell_sets for k in blocks]
    triangles = np.concatenate([d for d, _ in pairs]).astype(np.int64)
    surface = np.concatenate([t for _, t in pairs]).astype(int)
    _, first, cell = np.unique(np.sort(triangles, axis=1), axis=0, return_index=True,
                               return_inverse=True)
    member = np.unique(np.column_stack([cell.ravel(), surface]), axis=0)
    shared = np.flatnonzero(np.bincount(member[:, 0]) > 1)
    if len(shared):
        owners = [names.get(int(t), f"tag {t}")
                  for t in member[member[:, 0] == shared[0], 1].tolist()]
        raise InputError(f"{where}: {len(shared)} triangle(s) belong to more than one "
                         f"physical surface ({' and '.join(owners)}): each cell must belong "
                         "to exactly one physical surface: keep each surface in one "
                         "Physical Surface only")
    first = np.sort(first)
    return triangles[first], surface[first]


def _loop(triangles, points, where):
    """The boundary vertices counter-clockwise: the triangle edges used once, chained."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                            triangles[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, index, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    boundary = edges[index[count == 1]]
    following = dict(zip(boundary[:, 0].tolist(), boundary[:, 1].tolist()))
    require(len(following) == len(boundary), f"{where}: the boundary touches itself at a "
            "vertex: remesh the domain as one piece")
    loop, start = [int(boundary[0, 0])], int(boundary[0, 0])
    while following[loop[-1]] != start and len(loop) <= len(boundary):
        loop.append(following[loop[-1]])
    if len(loop) != len(boundary):
        where_ = points[boundary[0, 0]]
        raise InputError(f"{where}: the domain's boundary is not one loop (a hole, or "
                         f"pieces apart; one loop runs through ({where_[0]:g}, "
                         f"{where_[1]:g})): soilwater takes a simply connected domain")
    return np.array(loop)


def _groups(raw, tags, names, dims, used, loop, points, where):
    """The boundary group of every facet of ``loop`` and the names of the boundary groups,
    from the physical curves; and the names of the physical curves on no facet of
    ``loop`` (inside the domain)."""
    curve_tags = [tag for tag, dim in dims.items() if dim == 1]
    lines = [(b.data, t) for b, t in zip(raw.cells, tags) if b.type == "line"]
    data = np.concatenate([d for d, _ in lines] + [np.empty((0, 2), int)]).astype(np.int64)
    tag = np.concatenate([t for _, t in lines] + [np.empty(0, int)]).astype(int)
    named = np.isin(tag, curve_tags)
    require(named.any(), f"{where}: no physical curve names the boundary: add them, e.g. "
            "Physical Curve(\"base\") = {1};, and refer to them as [boundary.base]")
    renumber = np.full(max(int(used.max()), int(data.max())) + 1, -1)
    renumber[used] = np.arange(len(used))
    n = len(used)
    lines = np.sort(renumber[data[named]], axis=1)
    codes, first = np.unique(lines[:, 0] * n + lines[:, 1], return_index=True)
    ends = np.sort(np.stack([loop, np.roll(loop, -1)], axis=1), axis=1)
    facets = ends[:, 0] * n + ends[:, 1]
    k = np.minimum(np.searchsorted(codes, facets), len(codes) - 1)
    found = codes[k] == facets
    if not found.all():
        a, b = points[ends[np.argmin(found)]]
        raise InputError(f"{where}: {int((~found).sum())} boundary facet(s) belong to no "
                         f"physical curve (one from ({a[0]:g}, {a[1]:g}) to ({b[0]:g}, "
                         f"{b[1]:g})): add every boundary curve to a physical curve")
    facet_tag = tag[named][first[k]]
    groups = tuple(sorted({names[t] for t in np.unique(facet_tag).tolist()}))
    order = {tag_: groups.index(names[tag_]) for tag_ in np.unique(facet_tag).tolist()}
    curves = {names[t] for t in np.unique(tag[named]).tolist()}
    interior = tuple(sorted(curves - set(groups)))
    return np.vectorize(order.__getitem__, otypes=[int])(facet_tag), groups, interior
