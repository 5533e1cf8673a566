"""Result folders: marked, replaced whole or not at all, and readable by VTK (pyvista)."""

import json
import os

import numpy as np
import pandas as pd
import pytest
import pyvista

from soilwater.methods import METHODS
from soilwater.errors import InputError
from soilwater.case.loader import load_case
from soilwater.targets import MARKER, check_output_folder

FAST = ["time.steps=3", "time.end=1.0"]  # terzaghi in three steps: about a second


@pytest.fixture(scope="module", params=["efg", "fem-th"])
def result(request):
    """A small coupled run (meshless point cloud for efg, triangles for fem-th)."""
    return METHODS[request.param](load_case("terzaghi", FAST), progress=False)


def test_pvd_times_and_fields_are_read_by_vtk(tmp_path, result):
    out = result.write(tmp_path / "run")
    history = pd.read_csv(out / "history.csv")
    reader = pyvista.PVDReader(out / "fields.pvd")
    times = np.array(reader.time_values)
    assert times[0] == 0.0 and (np.diff(times) > 0).all()
    np.testing.assert_array_equal(times[1:], history.time)
    for t, snap in zip(times, result.snapshots, strict=True):
        reader.set_active_time_value(t)
        (block,) = reader.read()
        n = len(snap.points)          # the solver's points first (fem-th: then mid-sides)
        assert block.n_points == n if result.method == "efg" else block.n_points > n
        for name in ("u", "p_w", "p_eff", "q"):
            values = block.point_data[name]
            assert len(values) == block.n_points and np.isfinite(values).all()
            np.testing.assert_allclose(values[:n, :2] if name == "u" else values[:n],
                                       snap.point_data[name])
        assert not block.point_data["u"][:, 2].any()           # z = 0


def test_one_vtu_is_read_by_vtk(tmp_path, result):
    out = result.write(tmp_path / "run")
    mesh = pyvista.read(out / "fields_0003.vtu")
    snap = result.snapshots[3]
    assert mesh.n_points >= len(snap.points) and mesh.n_cells > 0
    np.testing.assert_allclose(mesh.point_data["p_w"][:len(snap.points)],
                               snap.point_data["p_w"])


def test_every_result_folder_holds_the_marker(tmp_path, result):
    out = result.write(tmp_path / "run")
    assert json.loads((out / MARKER).read_text())["written_by"] == "soilwater"


def test_new_empty_and_marked_folders_are_accepted(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "marked").mkdir()
    (tmp_path / "marked" / MARKER).write_text("{}\n")
    (tmp_path / "marked" / "history.csv").write_text("time\n1.0\n")
    for name in ("new", "empty", "marked"):
        assert check_output_folder(tmp_path / "x" / ".." / name) == tmp_path / name


def test_write_refuses_a_folder_soilwater_did_not_write(tmp_path, result):
    out = tmp_path / "data"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="did not write"):
        result.write(out)
    assert [p.name for p in tmp_path.iterdir()] == ["data"]
    assert [p.name for p in out.iterdir()] == ["notes.txt"]


def test_a_failed_swap_puts_the_previous_result_back(tmp_path, result, monkeypatch):
    out = result.write(tmp_path / "run")
    (out / "stale.txt").write_text("from the previous run")
    before = sorted(p.name for p in out.iterdir())
    rename = os.rename

    def rename_in_fails(src, dst):
        if str(src).endswith(".tmp"):
            raise OSError(30, "Read-only file system", str(dst))
        rename(src, dst)

    monkeypatch.setattr(os, "rename", rename_in_fails)
    with pytest.raises(OSError, match="Read-only"):
        result.write(out)
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
    assert sorted(p.name for p in out.iterdir()) == before


@pytest.mark.parametrize("method", ["efg", "fem-th"])
def test_output_times_are_history_rows_and_the_only_fields(method):
    case = load_case("terzaghi", ["time.steps=3", "time.end=1.0",
                                  'time.output=[0.5, "1 s"]'])
    result = METHODS[method](case, progress=False)
    assert [s.time for s in result.snapshots] == [0.0, 0.5, 1.0]
    assert result.history.time.tolist() == pytest.approx([1 / 3, 0.5, 2 / 3, 1.0])


def test_a_post_processor_warps_by_u_and_contours_p_w(tmp_path, result):
    out = result.write(tmp_path / "run")
    grid = pyvista.read(out / "fields_0001.vtu")
    assert grid.n_cells > 0 and grid["u"].shape == (grid.n_points, 3)
    warped = grid.warp_by_vector("u", factor=100.0)
    np.testing.assert_allclose(warped.points, grid.points + 100.0 * grid["u"])
    low, high = grid["p_w"].min(), grid["p_w"].max()
    assert high > low
    lines = grid.contour([0.5 * (low + high)], scalars="p_w")
    assert lines.n_points > 0                           # an isoline crosses the column
    np.testing.assert_allclose(lines["p_w"], 0.5 * (low + high), rtol=1e-9)
    units = json.loads((out / "summary.json").read_text())["field_units"]
    assert set(grid.point_data) | set(grid.cell_data) <= set(units)


def test_fem_th_is_written_on_its_own_quadratic_nodes(tmp_path):
    from skfem import CellBasis, ElementTriP2

    result = METHODS["fem-th"](load_case("terzaghi", FAST), progress=False)
    mesh = result.mesh()
    (block,) = mesh.cells
    snap = result.snapshots[-1]
    triangles = snap.cells[0][1]
    assert block.type == "triangle6" and np.array_equal(block.data[:, :3], triangles)
    skfem_mesh = type_mesh(snap.points, triangles)
    nodes = CellBasis(skfem_mesh, ElementTriP2()).doflocs.T
    np.testing.assert_allclose(mesh.points[:, :2], nodes, atol=1e-12)
    velocity = mesh.point_data["velocity"]
    assert velocity.shape == (len(nodes), 3) and np.abs(velocity[len(snap.points):]).max() > 0
    # each mid-side node lies halfway along its cell's edge, in VTK's edge order
    corners, mids = mesh.points[block.data[:, :3]], mesh.points[block.data[:, 3:]]
    np.testing.assert_allclose(mids, 0.5 * (corners + np.roll(corners, -1, axis=1)),
                               atol=1e-12)


def type_mesh(points, triangles):
    """A scikit-fem triangle mesh in the given vertex order."""
    from skfem import MeshTri

    return MeshTri(np.ascontiguousarray(points.T), np.ascontiguousarray(triangles.T))


def test_cell_strains_of_a_homogeneous_compression_are_its_log_strain():
    case = load_case("unconfined-compression", ["time.steps=4"])
    for method in ("efg-paper", "fem-p1p1"):
        result = METHODS[method](case, progress=False)
        mesh = result.mesh()
        height = case.geometry.height
        top = result.snapshots[-1].points[:, 1].max()
        strain = mesh.cell_data["log_strain"][0].reshape(-1, 3, 3)
        np.testing.assert_allclose(strain[:, 1, 1], np.log(top / height), rtol=1e-4)
        assert (mesh.cell_data["shear_strain"][0] > 0).all()
