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
from soilwater.results import MARKER, check_output_folder

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
        assert block.n_points == len(snap.points)
        for name in ("u", "p_w", "p_eff", "q"):
            values = block.point_data[name]
            assert len(values) == block.n_points and np.isfinite(values).all()
            np.testing.assert_allclose(values, snap.point_data[name])


def test_one_vtu_is_read_by_vtk(tmp_path, result):
    out = result.write(tmp_path / "run")
    mesh = pyvista.read(out / "fields_0003.vtu")
    snap = result.snapshots[3]
    assert mesh.n_points == len(snap.points) and mesh.n_cells > 0
    np.testing.assert_allclose(mesh.point_data["p_w"], snap.point_data["p_w"])


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
