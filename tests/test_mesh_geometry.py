"""Cases on a user's mesh (geometry.mesh, soilwater.geometry.mesh): read with meshio or
meshed by gmsh, physical curves as boundary groups, every triangle method on it, and the
one-line refusals of a mesh soilwater cannot take."""

import os
import re
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

import soilwater
from soilwater.case.loader import load_case
from soilwater.case.validation import case_from_dict
from soilwater.errors import InputError
from soilwater.fem.spaces import initial_mesh
from soilwater.geometry.mesh import read_mesh

DATA = Path(__file__).parent / "data"


def write_msh(path, points, triangles, lines, regions=None):
    """A gmsh file (format 2.2) of ``triangles`` (T, 3) on ``points`` (N, 2) with the
    physical curves ``lines`` ``{name: (F, 2) vertex pairs}`` and the physical surfaces
    ``regions`` ``{name: (T,) bool}`` (one surface ``soil`` by default)."""
    regions = regions or {"soil": np.ones(len(triangles), bool)}
    names = list(lines) + list(regions)
    cells = [("line", np.asarray(pairs)) for pairs in lines.values()]
    cells += [("triangle", np.asarray(triangles)[mask]) for mask in regions.values()]
    tags = [np.full(len(block[1]), k + 1) for k, block in enumerate(cells)]
    meshio.write(path, meshio.Mesh(np.column_stack([points, np.zeros(len(points))]), cells,
                                   cell_data={"gmsh:physical": tags,
                                              "gmsh:geometrical": tags},
                                   field_data={name: np.array([k + 1, 1 + (k >= len(lines))])
                                               for k, name in enumerate(names)}),
                 file_format="gmsh22", binary=False)


def grid_as_mesh(case, path):
    """``case`` (a rectangle) written as a mesh: the triangles of its FEM reference, the
    four edges as physical curves of their own names."""
    mesh = initial_mesh(case, "fem-p1p1")
    points, loop = mesh.p.T, case.boundary_loop()
    ends = np.stack([loop, np.roll(loop, -1)], axis=1)
    edge = case.geometry.edge_of(points[ends[:, 0]], points[ends[:, 1]])
    write_msh(path, points, mesh.t.T, {name: ends[edge == k]
                                       for k, name in enumerate(case.geometry.edges)})


def on_mesh(case, path):
    """The case with its rectangle replaced by the mesh file ``path``."""
    data = case.to_dict()
    data["geometry"] = {"mesh": str(path)}
    data.pop("discretisation")
    return case_from_dict(data)


@pytest.fixture
def terzaghi_mesh(tmp_path):
    grid = load_case("terzaghi", ("discretisation.nx=3",))
    grid_as_mesh(grid, tmp_path / "column.msh")
    return grid, on_mesh(grid, tmp_path / "column.msh")


def test_a_rectangle_read_as_a_mesh_is_the_grid_case(terzaghi_mesh):
    """Terzaghi's column written as a .msh (the FEM reference's triangles, its four edges
    as physical curves) gives the grid case's run: the same nodes, triangles and boundary
    data, so fem-th and efg-paper (Delaunay cells on the same nodes) give the same
    history to 1e-9, and efg (the mesh's triangles as its cells, where the grid case
    takes Delaunay's of cocircular nodes) the same pore pressure to 1e-3 of the load."""
    grid, mesh = terzaghi_mesh
    assert np.array_equal(np.sort(mesh.nodes(), axis=0), np.sort(grid.nodes(), axis=0))
    for method, tol in (("fem-th", 1e-9), ("efg-paper", 1e-9), ("efg", 1e-3)):
        a = soilwater.solve(mesh, method, progress=False).history
        b = soilwater.solve(grid, method, progress=False).history
        np.testing.assert_allclose(a["p_w@p5"], b["p_w@p5"], rtol=0, atol=tol * 1e-3)
        assert a["settlement"].iloc[-1] == pytest.approx(b["settlement"].iloc[-1], rel=tol)


def test_a_user_slope_runs_in_every_triangle_method():
    """The slope of fill over clay (tests/data/slope.msh, written by gmsh from slope.geo:
    six physical curves, two physical surfaces, each its own soil) loaded on its crest:
    every triangle method runs it, and each one's crest settlement and pore pressure
    under the crest lie within 6 % of fem-th's (measured: efg 4.6 % stiffer, the most,
    where the soils meet and at the load's edge; efg-paper 1.4 %, fem-p1p1-stab 0.9 %;
    pore pressures within 2.2 %). The loaded crest has its own columns: pressure@crest
    the applied 50 kPa times the load factor (to 1e-6 of it), settlement@crest the mean
    settlement of its vertices, within 6 % of fem-th's too."""
    case = load_case(DATA / "slope.toml")
    assert case.geometry.mesh.groups == ("base", "crest", "face", "ground", "left", "right")
    assert case.geometry.mesh.regions == ("clay", "fill")
    assert [m.E for m in case.material().materials] == [10000.0, 30000.0]
    runs = {m: soilwater.solve(case, m, progress=False).history
            for m in ("efg", "efg-paper", "fem-th", "fem-p1p1-stab")}
    ref = runs["fem-th"].iloc[-1]
    assert ref["settlement"] > 0
    for method, history in runs.items():
        last = history.iloc[-1]
        assert last["settlement"] == pytest.approx(ref["settlement"], rel=0.06), method
        assert last["p_w@under"] == pytest.approx(ref["p_w@under"], rel=0.06), method
        assert last["settlement@crest"] == pytest.approx(ref["settlement@crest"],
                                                         rel=0.06), method
        np.testing.assert_allclose(history["pressure@crest"],
                                   50 * np.minimum(history["time"] / 10, 1), rtol=0,
                                   atol=5e-5, err_msg=method)


def test_a_geo_file_is_meshed_by_gmsh():
    """The same slope from its .geo: gmsh meshes it into the vertices of the .msh."""
    pytest.importorskip("gmsh")
    geo, msh = read_mesh(DATA / "slope.geo"), read_mesh(DATA / "slope.msh")
    assert len(geo.points) == len(msh.points) and geo.groups == msh.groups


def test_a_geostatic_start_needs_a_level_ground():
    with pytest.raises(InputError, match="surface falls to y = 6 m at x = 20 m"):
        load_case(DATA / "slope.toml", ("initial.stress=geostatic",))


def test_quadrilateral_methods_refuse_a_triangle_mesh():
    case = load_case(DATA / "slope.toml")
    with pytest.raises(InputError, match="fem-q1q1 needs a structured grid"):
        soilwater.solve(case, "fem-q1q1", progress=False)


def _square(tmp_path, name="square.msh", shift=0.0, named=("bottom", "right", "top",
                                                            "left")):
    """A unit square of two triangles, its sides as physical curves ``named`` (None:
    left out)."""
    points = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) + shift
    sides = [[0, 1], [1, 2], [2, 3], [3, 0]]
    write_msh(tmp_path / name, points, [[0, 1, 2], [0, 2, 3]],
              {n: [s] for n, s in zip(named, sides) if n})
    return tmp_path / name


@pytest.mark.parametrize("change, message", [
    ({"geometry": {"mesh": "nowhere.msh"}}, "does not exist"),
    ({"geometry": {"mesh": "square.vtk"}}, "give a gmsh mesh"),
    ({"geometry": {"mesh": "square.msh", "width": 1.0}}, "give mesh and no width"),
    ({"discretisation": {"nx": 3}}, "discretisation.nx: a case on a mesh"),
    ({"boundary": {"side": {}}}, "unknown boundary group (physical curve of geometry.mesh) "
                                 "'side'"),
    ({"boundary": {"bottom": {"pad": {"from": 0.0, "to": 0.5}}}},
     "named segments are for the rectangle"),
    ({"boundary": {"bottom": {"uy": "rigid"}}}, "'rigid' applies to a rectangle"),
    ({"boundary": {"bottom": {"ux": "fixed"}}}, "not supported along y"),
    ({"boundary": {"bottom": {"ux": "fixed"}, "left": {"uy": "fixed"}}},
     "not supported against rotation"),
    ({"probes": {"out": [2.0, 0.5]}}, "probes.out = [2.0, 0.5] lies outside"),
])
def test_a_bad_mesh_case_is_refused_in_one_line(tmp_path, change, message):
    _square(tmp_path)
    (tmp_path / "square.vtk").write_text("")
    data = {"geometry": {"mesh": "square.msh"}, "material": {"model": "elastic",
                                                              "E": 1e3, "nu": 0.3},
            "boundary": {"bottom": {"displacement": "fixed"},
                         "left": {"displacement": "roller"}},
            "time": {"end": 1.0, "steps": 1}}
    data.update(change)
    data["geometry"] = {k: str(tmp_path / v) if k == "mesh" else v
                        for k, v in data["geometry"].items()}
    with pytest.raises(InputError, match=re.escape(message)):
        case_from_dict(data)


@pytest.mark.parametrize("kwargs, message", [
    ({"shift": 1.0}, "lower-left corner is at (1, 1), not at the origin"),
    ({"named": ("bottom", "right", None, "left")}, "1 boundary facet(s) belong to no "
                                                   "physical curve"),
    ({"named": (None, None, None, None)}, "no physical curve names the boundary"),
])
def test_a_mesh_soilwater_cannot_take_is_refused_in_one_line(tmp_path, kwargs, message):
    path = _square(tmp_path, **kwargs)
    with pytest.raises(InputError, match=re.escape(message)):
        read_mesh(path)


def test_a_mesh_with_a_hole_is_refused(tmp_path):
    """A square frame (a hole in the middle): two boundary loops."""
    outer = np.array([[0, 0], [3, 0], [3, 3], [0, 3]], float)
    inner = np.array([[1, 1], [2, 1], [2, 2], [1, 2]], float)
    points = np.vstack([outer, inner])
    triangles = [[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6],
                 [3, 0, 4], [3, 4, 7]]
    write_msh(tmp_path / "frame.msh", points, triangles,
              {"outer": [[0, 1], [1, 2], [2, 3], [3, 0]],
               "inner": [[4, 5], [5, 6], [6, 7], [7, 4]]})
    with pytest.raises(InputError, match="not one loop"):
        read_mesh(tmp_path / "frame.msh")


def test_a_geo_file_without_gmsh_says_how_to_get_it(monkeypatch):
    """The message is the line itself, not wrapped in a 'cannot be read' one."""
    monkeypatch.setitem(sys.modules, "gmsh", None)
    with pytest.raises(InputError, match=r"^geometry\.mesh = '[^']*slope\.geo' needs the "
                                         r"gmsh package .*soilwater\[geometry\]"):
        read_mesh(DATA / "slope.geo")


def test_a_geo_file_gmsh_cannot_mesh_gives_gmsh_s_message(tmp_path):
    pytest.importorskip("gmsh")
    (tmp_path / "bad.geo").write_text("Point(1) = {0, 0, 0;\n")
    with pytest.raises(InputError, match=r"^geometry\.mesh = '[^']*bad\.geo': gmsh could "
                                         r"not mesh it \(.*syntax error.*\): correct "
                                         r"the geometry"):
        read_mesh(tmp_path / "bad.geo")


@pytest.mark.parametrize("make, message", [
    (lambda p: p.write_bytes(b""), "is empty (0 bytes)"),
    (lambda p: p.write_text("not a mesh\n"), "is not a gmsh mesh: write it with gmsh"),
    (lambda p: p.write_bytes(bytes(range(256))), "is not a gmsh mesh"),
    (lambda p: p.mkdir(), "is a folder, not a regular file"),
    (os.mkfifo, "is a device, pipe or socket, not a regular file"),
])
def test_a_mesh_file_that_is_no_mesh_is_refused_in_one_line(tmp_path, make, message):
    path = tmp_path / "broken.msh"
    make(path)
    with pytest.raises(InputError, match="^" + re.escape(f"geometry.mesh = {str(path)!r} "
                                                         f"{message}")):
        read_mesh(path)


def test_dev_null_is_not_a_regular_file():
    with pytest.raises(InputError, match="^" + re.escape("geometry.mesh = '/dev/null' is a "
                                                         "device, pipe or socket, not a "
                                                         "regular file")):
        read_mesh("/dev/null")


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_non_finite_vertex_is_refused(tmp_path, value):
    points = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], float)
    points[2:4, 1] = value
    write_msh(tmp_path / "nan.msh", points, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
              {"outline": [[0, 1], [1, 2], [2, 3], [3, 0]]})
    with pytest.raises(InputError, match=re.escape("geometry.mesh: 2 vertex(es) have a "
                                                   "non-finite coordinate (NaN or "
                                                   "infinite), the first node 3 in the "
                                                   "file's order")):
        read_mesh(tmp_path / "nan.msh")


TWO_SURFACES = """Point(1) = {0, 0, 0, 0.5}; Point(2) = {1, 0, 0, 0.5};
Point(3) = {1, 1, 0, 0.5}; Point(4) = {0, 1, 0, 0.5};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Curve("outline") = {1, 2, 3, 4};
Physical Surface("soil") = {1}; Physical Surface("other") = {1};
"""


@pytest.mark.parametrize("source", ["msh2", "geo"])
def test_a_triangle_in_two_physical_surfaces_is_refused(tmp_path, source):
    """msh2 repeats such a triangle once per surface (written here by meshio: one of the
    two triangles in both); gmsh's msh4 (what a .geo is meshed into) gives its entity both
    surfaces, and meshio keeps only the first."""
    if source == "geo":
        pytest.importorskip("gmsh")
        path, count = tmp_path / "square.geo", r"\d+"
        path.write_text(TWO_SURFACES)
    else:
        path, count = tmp_path / "square.msh", "1"
        write_msh(path, np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float),
                  [[0, 1, 2], [0, 2, 3]], {"outline": [[0, 1], [1, 2], [2, 3], [3, 0]]},
                  {"soil": np.array([True, True]), "other": np.array([True, False])})
    with pytest.raises(InputError, match=rf"^geometry\.mesh: {count} triangle\(s\) belong "
                                         r"to more than one physical surface \(soil and "
                                         r"other\): each cell must belong to exactly one "
                                         r"physical surface"):
        read_mesh(path)


def _layers(tmp_path):
    """Two unit squares stacked (regions clay below, sand above), the interface between
    them a physical curve of its own."""
    points = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 2], [1, 2]], float)
    write_msh(tmp_path / "layers.msh", points, [[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4]],
              {"bottom": [[0, 1]], "right": [[1, 2], [2, 5]], "top": [[5, 4]],
               "left": [[4, 3], [3, 0]], "interface": [[2, 3]]},
              {"clay": np.array([True, True, False, False]),
               "sand": np.array([False, False, True, True])})
    return tmp_path / "layers.msh"


def test_an_interior_physical_curve_takes_no_boundary_condition(tmp_path):
    """A mesh may name a curve between its regions; a [boundary.NAME] on it is refused
    as such, not as an unknown boundary group."""
    mesh = read_mesh(_layers(tmp_path))
    assert mesh.groups == ("bottom", "left", "right", "top")
    assert mesh.interior == ("interface",) and mesh.regions == ("clay", "sand")
    data = {"geometry": {"mesh": str(tmp_path / "layers.msh")},
            "material": {"model": "elastic", "E": 1e3, "nu": 0.3},
            "boundary": {"bottom": {"displacement": "fixed"},
                         "left": {"displacement": "roller"}},
            "time": {"end": 1.0, "steps": 1}}
    assert case_from_dict(data).geometry.mesh.interior == ("interface",)
    data["boundary"]["interface"] = {"water": "drained"}
    with pytest.raises(InputError, match=re.escape(
            "boundary.interface: 'interface' is an interior curve of geometry.mesh "
            "(between regions, not on the outline), so it cannot carry a boundary "
            "condition")):
        case_from_dict(data)


def test_the_resolved_case_names_the_mesh_file_and_reloads(tmp_path):
    """A mesh case's dict holds the mesh's absolute path and no [discretisation], and
    replace() (which goes through that dict) reloads it."""
    case = load_case(DATA / "slope.toml")
    data = case.to_dict()
    assert data["geometry"] == {"shape": "mesh", "mesh": str((DATA / "slope.msh").resolve())}
    assert data["discretisation"] == {}
    assert len(case.replace("time.steps=2").nodes()) == len(case.nodes())


FOOTING_GRID = ("discretisation.x=[[1.0, 2], [10.0, 9]]",
                "discretisation.y=[[9.0, 9], [10.0, 2]]", "time.steps=5", "time.end=5")


def _footing_on_mesh(tmp_path, footing):
    """The built-in strip footing (coarse, to 0.05 B) and the same soil as a .msh whose
    footing (top facets with x <= 0.5 m) is the physical curve ``pad``; ``footing`` is the
    group's table."""
    grid = load_case("strip-footing", FOOTING_GRID)
    mesh = initial_mesh(grid, "fem-p1p1")
    points, loop = mesh.p.T, grid.boundary_loop()
    ends = np.stack([loop, np.roll(loop, -1)], axis=1)
    edge = np.array(grid.geometry.edges)[grid.geometry.edge_of(points[ends[:, 0]],
                                                               points[ends[:, 1]])]
    edge[(edge == "top") & (points[ends].max(axis=1)[:, 0] <= 0.5 + 1e-9)] = "pad"
    write_msh(tmp_path / "soil.msh", points, mesh.t.T,
              {name: ends[edge == name] for name in ("left", "right", "bottom", "top", "pad")})
    data = grid.to_dict()
    data["geometry"] = {"mesh": str(tmp_path / "soil.msh")}
    data.pop("discretisation")
    data["boundary"]["top"].pop("footing")
    data["boundary"]["pad"] = footing
    return grid, case_from_dict(data)


def test_a_footing_on_a_mesh_group_is_the_rectangle_s_footing(tmp_path):
    """A rigid footing given as a mesh's boundary group (``uy = "footing"``) is the named
    segment of the rectangle it replaces: the same settlement@NAME and pressure@NAME
    history in fem-th and efg-paper (same nodes and constraints, to 1e-9 of the pressure),
    and its table reloads from the resolved case."""
    grid, mesh = _footing_on_mesh(tmp_path, {"ux": "free", "uy": "footing",
                                             "settlement_rate": 0.01})
    (_, seg), = mesh.boundary.segments()
    assert seg.whole and seg.footing and mesh.to_dict()["boundary"]["pad"]["uy"] == "footing"
    assert case_from_dict(mesh.to_dict()) == mesh
    for method in ("fem-th", "efg-paper"):
        a = soilwater.solve(mesh, method, progress=False).history
        b = soilwater.solve(grid, method, progress=False).history
        np.testing.assert_allclose(a["settlement@pad"], b["settlement@footing"], rtol=1e-12)
        scale = np.abs(b["pressure@footing"]).max()
        assert scale > 0
        np.testing.assert_allclose(a["pressure@pad"], b["pressure@footing"], rtol=0,
                                   atol=1e-9 * scale)


def test_a_load_controlled_footing_on_a_mesh_group_carries_its_force(tmp_path):
    """A footing group under load control (``force``) settles by one unknown whose
    pressure@NAME is the force over the footing's current width at every level: within
    1 % of force / B (the smooth footing's ends spread by 0.2 % on this mesh), in
    fem-p1p1-stab and efg."""
    force = 2.0
    _, mesh = _footing_on_mesh(tmp_path, {"uy": "footing", "force": force})
    for method in ("fem-p1p1-stab", "efg"):
        history = soilwater.solve(mesh, method, progress=False).history
        assert history["settlement@pad"].iloc[-1] > 0, method
        np.testing.assert_allclose(history["pressure@pad"].iloc[1:], force / 0.5, rtol=1e-2,
                                   err_msg=method)


@pytest.mark.parametrize("pad, message", [
    ({"uy": "footing"}, "boundary.pad.uy = 'footing' needs exactly one of settlement_rate"),
    ({"uy": "footing", "settlement_rate": 0.01, "traction": [0.0, -1.0]},
     "boundary.pad.traction: a footing carries no traction"),
    ({"force": 1.0}, "boundary.pad.force applies to a footing only"),
    ({"ux": "rigid"}, "boundary.pad: 'rigid' applies to a rectangle's top or bottom edge: "
                      "use \"footing\""),
])
def test_a_footing_group_s_bad_table_is_refused_in_one_line(tmp_path, pad, message):
    with pytest.raises(InputError, match=re.escape(message)):
        _footing_on_mesh(tmp_path, pad)
