"""Result folders: marked, replaced whole or not at all, and readable by VTK (pyvista)."""

import errno
import json
import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import pyvista

from soilwater.methods import METHODS
from soilwater.errors import InputError
from soilwater.case.loader import load_case
from soilwater.locks import claim
from soilwater.studies.harness.folder import (REPORT_MARKER, check_report_folder,
                                              mark_report_folder)
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


def test_the_summary_says_how_the_result_was_made(tmp_path, result):
    """summary.json names the date, the command line, the source commit (in this
    checkout) and, for a case on a mesh, the mesh's hash, counts and regions."""
    summary = json.loads((result.write(tmp_path / "run") / "summary.json").read_text())
    made = summary["provenance"]
    assert made["date"].startswith("20") and made["date"].endswith("Z")
    assert isinstance(made["command"], str)
    assert made["source"] is None or len(made["source"].removesuffix("-dirty")) == 40
    assert "mesh" not in made and {"numpy", "meshio", "soilwater"} <= set(summary["versions"])


def test_a_result_on_a_mesh_names_the_mesh_it_was_made_on(tmp_path):
    import soilwater
    from soilwater.results import provenance

    case = soilwater.load_case("embankment")
    made, mesh = provenance(case), case.geometry.mesh
    assert made["mesh"] == {"path": str(mesh.path), "sha256": mesh.digest,
                            "vertices": len(mesh.points),
                            "triangles": len(mesh.triangles),
                            "regions": list(mesh.regions)}
    assert len(made["mesh"]["sha256"]) == 64 and made["mesh"]["regions"]


def test_the_marker_lists_the_files_written(tmp_path, result):
    out = result.write(tmp_path / "run")
    files = json.loads((out / MARKER).read_text())["files"]
    assert files == sorted(p.name for p in out.iterdir() if p.name != MARKER)
    assert {"summary.json", "history.csv", "fields.pvd", "fields_0000.vtu"} <= set(files)


def _tree(folder):
    return {p.relative_to(folder): p.read_bytes() if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


def test_a_previous_result_holding_the_users_files_is_refused(tmp_path, result):
    out = result.write(tmp_path / "stab")
    (out / "pw.png").write_bytes(b"the user's figure")
    (out / "notes").mkdir()
    (out / "notes" / "a.txt").write_text("mine")
    before = _tree(tmp_path)
    with pytest.raises(InputError) as refused:
        check_output_folder(out, "--out")
    assert str(refused.value) == (
        f"--out {out} is a previous result holding 2 entries soilwater did not write "
        "(notes/, pw.png), which replacing it would delete; move them out of it, or "
        "choose another --out")
    with pytest.raises(InputError, match=r"^folder .* 2 entries .*another folder$"):
        result.write(out)
    assert _tree(tmp_path) == before


def test_a_refusal_names_three_entries_and_counts_them_all(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / MARKER).write_text(json.dumps({"files": ["history.csv"]}))
    (out / "history.csv").write_text("time\n1.0\n")
    for name in ("e.txt", "d.txt", "c.txt", "b.txt", "a.txt"):
        (out / name).write_text("mine")
    with pytest.raises(InputError, match=r"holding 5 entries .* \(a\.txt, b\.txt, "
                       r"c\.txt, \.\.\.\)"):
        check_output_folder(out)


def test_files_left_in_the_folder_during_the_run_are_refused_at_write_time(
        tmp_path, result, monkeypatch):
    out = result.write(tmp_path / "run")
    before = _tree(tmp_path)
    write_fields = type(result)._write_fields

    def user_drops_a_file(self, folder):
        write_fields(self, folder)
        (out / "pw.png").write_bytes(b"saved while the run went on")

    monkeypatch.setattr(type(result), "_write_fields", user_drops_a_file)
    with pytest.raises(InputError, match=r"1 entry soilwater did not write \(pw\.png\)"):
        result.write(out)
    assert _tree(tmp_path) == {**before, out.relative_to(tmp_path) / "pw.png":
                               b"saved while the run went on"}


def test_a_result_whose_marker_lists_no_files_is_known_by_its_names(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / MARKER).write_text('{"written_by": "soilwater"}\n')
    for name in ("summary.json", "history.csv", "fields.pvd", "fields_0012.vtu"):
        (out / name).write_text("")
    assert check_output_folder(out) == out
    (out / "pw.png").write_bytes(b"")
    with pytest.raises(InputError, match=r"1 entry soilwater did not write \(pw\.png\)"):
        check_output_folder(out)


_HOLD = """import sys
from soilwater.locks import claim
with claim(sys.argv[1]):
    print("held", flush=True)
    sys.stdin.read()
"""


def test_a_claimed_folder_is_refused_to_a_second_process_until_released(tmp_path,
                                                                         result):
    out = tmp_path / "run"
    holder = subprocess.Popen([sys.executable, "-c", _HOLD, str(out)], text=True,
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert holder.stdout.readline() == "held\n"
        lock = tmp_path / ".run.lock"
        message = (f"--out {out} is being written by another soilwater run (process "
                   f"{holder.pid}, lock {lock}); wait for it to end, or choose another "
                   "--out")
        with pytest.raises(InputError) as refused, claim(out, "--out"):
            pass
        assert str(refused.value) == message
        with pytest.raises(InputError, match="being written by another soilwater run"):
            result.write(out)
        assert [p.name for p in tmp_path.iterdir()] == [".run.lock"]
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)
    assert list(tmp_path.iterdir()) == []
    assert result.write(out) == out and not lock.exists()


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path, result):
    (tmp_path / ".run.lock").write_text("999999999\n")
    assert result.write(tmp_path / "run") == tmp_path / "run"
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


def test_a_claim_is_released_and_its_folders_removed_on_failure(tmp_path):
    out = tmp_path / "a" / "b" / "run"
    with pytest.raises(KeyboardInterrupt), claim(out) as folder:
        assert folder == out and (tmp_path / "a" / "b" / ".run.lock").is_file()
        with claim(out):                 # this process holds it already: Result.write
            pass
        assert (tmp_path / "a" / "b" / ".run.lock").is_file()
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux /proc")
def test_a_folder_that_cannot_be_created_is_named_as_given(result):
    with pytest.raises(InputError) as refused:
        result.write("/proc/x", what="--out")
    message = str(refused.value)
    assert message.startswith("--out /proc/x: c") and ".tmp" not in message
    assert ".lock" not in message


def test_a_write_error_names_the_file_in_the_result_folder(tmp_path, result,
                                                           monkeypatch):
    import meshio

    def full(path, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(meshio, "write", full)
    with pytest.raises(OSError) as failed:
        result.write(tmp_path / "run")
    assert failed.value.filename == str(tmp_path / "run" / "fields_0000.vtu")
    assert list(tmp_path.iterdir()) == []


def test_report_folders_new_empty_marked_or_soilwaters_are_accepted(tmp_path):
    (tmp_path / "empty").mkdir()
    marked = mark_report_folder(tmp_path / "marked")
    (marked / "tables").mkdir()
    assert json.loads((marked / REPORT_MARKER).read_text())["written_by"] == "soilwater"
    earlier = tmp_path / "earlier"
    (earlier / "studies").mkdir(parents=True)
    (earlier / "REPORT.md").write_text("# soilwater report (quick)\n\ntext\n")
    (earlier / "bench.md").write_text("")
    for name in ("new", "empty", "marked", "earlier"):
        assert check_report_folder(tmp_path / "x" / ".." / name) == tmp_path / name


def test_report_folders_soilwater_did_not_write_are_refused(tmp_path, monkeypatch):
    work = tmp_path / "work"
    (work / "src").mkdir(parents=True)
    monkeypatch.chdir(work)
    with pytest.raises(InputError, match=r"^--out \. \(= .*\): the current folder or "
                       "a folder holding it cannot be a report folder; name a new or "
                       "empty folder, or a report soilwater wrote$"):
        check_report_folder(".", "--out")
    run = tmp_path / "run"
    run.mkdir()
    (run / MARKER).write_text("{}")
    with pytest.raises(InputError, match=f"is a result of soilwater run .*{MARKER}"):
        check_report_folder(run)
    notes = tmp_path / "notes"
    (notes / "studies").mkdir(parents=True)
    (notes / "REPORT.md").write_text("# My report\n")
    with pytest.raises(InputError) as refused:
        check_report_folder(notes, "--out")
    assert str(refused.value) == (
        f"--out {notes}: {notes / 'REPORT.md'} was not written by soilwater report; move "
        "it out of the folder, or name a new or empty folder, or a report soilwater wrote")
    (tmp_path / "data" / "src").mkdir(parents=True)
    with pytest.raises(InputError, match=r"is not a soilwater report \(no "
                       r"\.soilwater-report\) and holds 1 entry \(src/\)"):
        check_report_folder(tmp_path / "data", "--out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "notes", "run", "work"]


def test_a_failed_swap_puts_the_previous_result_back(tmp_path, result, monkeypatch):
    out = result.write(tmp_path / "run")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    rename = os.rename

    def rename_in_fails(src, dst):
        if str(src).endswith(".tmp"):
            raise OSError(30, "Read-only file system", str(dst))
        rename(src, dst)

    monkeypatch.setattr(os, "rename", rename_in_fails)
    with pytest.raises(OSError, match="Read-only"):
        result.write(out)
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


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
