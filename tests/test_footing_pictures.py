"""The strip-footing pictures (:mod:`soilwater.studies.footing.pictures`,
:mod:`soilwater.studies.footing.gif`) from a tiny real run: the report's tasks write PNGs
that open and one GIF per method with one frame per snapshot (or every k-th), the section
names what they wrote, the distortion count rates the undeformed mesh clean and a mesh
with a node pushed through its neighbours inverted, and a failing writer leaves nothing
behind."""

import copy

import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

from soilwater.studies.footing import gif, pictures, pictures_report
from soilwater.efg.solver import solve as efg_solve
from soilwater.fem.solver import solve as fem_solve
from soilwater.case.loader import load_case

#: 6 x 6 nodes, 10 steps to a settlement of 0.1 B.
TINY = ("discretisation.x=[[1.0, 2], [10.0, 3, 3.0]]",
        "discretisation.y=[[9.0, 3, 0.3333333333333333], [10.0, 2]]", "time.steps=10",
        "time.end=10")


@pytest.fixture(scope="module")
def tiny():
    case = load_case("strip-footing", list(TINY))
    return [efg_solve(case, progress=False), fem_solve(case, "fem-th", progress=False)]


def test_tasks_write_pngs_gifs_and_a_section_naming_them(tiny, tmp_path):
    """The report's tasks after the runs (given here): a table, two PNGs that open, one
    GIF per method with all 11 snapshots as frames; nothing else in the folders."""
    for sub in ("tables", "figures"):      # as soilwater.studies.report.make_report
        (tmp_path / sub).mkdir()
    data, written = pictures_report.write(tmp_path, tiny)
    figures = tmp_path / "figures"
    names = sorted(p.name for p in figures.iterdir())
    assert names == ["footing_deformed.png", "footing_efg.gif", "footing_fem-th.gif",
                     "footing_pore_pressure.png"]
    assert sorted(p.name for p in written if p.parent == figures) == names
    for name in names:
        with Image.open(figures / name) as image:
            image.load()
            assert min(image.size) > 300
            if name.endswith(".gif"):
                assert image.n_frames == 11
    table = data["footing deformation"]
    assert table.reached.tolist() == pytest.approx([0.1, 0.1])
    assert (table.dp_min < table.dp_max).all()
    text = "\n".join(pictures_report.section(data))
    for name in names:
        assert f"(figures/{name})" in text
    assert f"efg {table.eps_s_edge[0]:.3g}" in text


def test_every_kth_snapshot_with_the_last(tiny, tmp_path):
    path = gif.animation(tiny[1], tmp_path / "fem.gif", most=5)
    with Image.open(path) as image:
        assert image.n_frames == 5  # snapshots 0, 3, 6, 9 and 10
    assert [p.name for p in tmp_path.iterdir()] == ["fem.gif"]


def test_distorted_elements_known_good_and_known_bad(tiny, tmp_path):
    """The undeformed mesh has no element below the angle threshold; pushing a node
    through the opposite corner of its patch inverts elements, counted as distorted and
    inverted, with NaN eps_s (drawn magenta)."""
    fem = tiny[1]
    clean = copy.copy(fem)
    clean.snapshots = fem.snapshots[:1]
    assert pictures.measures([clean]).loc[0, ["distorted", "inverted"]].tolist() == [0, 0]
    bad = copy.copy(fem)
    last = copy.deepcopy(fem.snapshots[-1])
    points = fem.snapshots[0].points
    node = int(np.argmin(np.linalg.norm(points - [1.0, 9.0], axis=1)))  # interior
    last.points[node] += [3.0, 3.0]       # past its neighbours, at most 2.2 m away
    bad.snapshots = fem.snapshots[:-1] + [last]
    row = pictures.measures([bad]).iloc[0]
    assert row.inverted >= 1 and row.distorted >= row.inverted
    with Image.open(pictures.deformed_figure([bad], tmp_path / "bad.png")) as image:
        image.load()


def test_a_failing_writer_leaves_nothing(tiny, tmp_path, monkeypatch):
    """A GIF that fails after two frames and a PNG whose save fails after writing leave
    no file behind, and an earlier picture stays as it was."""
    calls = []

    def grab_then_fail(self, **kwargs):
        calls.append(1)
        if len(calls) > 2:
            raise OSError("disk full")
        return original_grab(self, **kwargs)
    original_grab = gif.PillowWriter.grab_frame
    monkeypatch.setattr(gif.PillowWriter, "grab_frame", grab_then_fail)
    with pytest.raises(OSError, match="disk full"):
        gif.animation(tiny[0], tmp_path / "efg.gif")
    assert list(tmp_path.iterdir()) == []

    earlier = tmp_path / "deformed.png"
    earlier.write_bytes(b"earlier")
    original_save = Figure.savefig

    def save_then_fail(self, *args, **kwargs):
        original_save(self, *args, **kwargs)
        raise OSError("disk full")
    monkeypatch.setattr(Figure, "savefig", save_then_fail)
    with pytest.raises(OSError, match="disk full"):
        pictures.deformed_figure(tiny, earlier)
    assert list(tmp_path.iterdir()) == [earlier]
    assert earlier.read_bytes() == b"earlier"
