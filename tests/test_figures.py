"""The report's figures are slides: every figure a study draws from its saved output
(``figures(root, data)`` on ``reports/studies/NAME.pkl``) and the strip footing's
pictures (from a tiny real run) is about 16:9, at least 1280 px wide, and labels every
axis that shows data, and every colour bar, with a unit in square brackets; a quick
report's figures carry its label. (The stability study's inf-sup figure is the library's,
:mod:`soilwater.diagnostics.figures`, not saved through the harness: not checked.)"""

import re

import pytest

from soilwater.case.loader import load_case
from soilwater.efg.solver import solve as efg_solve
from soilwater.fem.solver import solve as fem_solve
from soilwater.studies.footing import pictures
from soilwater.studies.harness import figures, quick
from soilwater.studies.harness.paths import ROOT
from soilwater.studies.harness.study import load
from soilwater.studies.registry import STUDIES

#: The studies whose figures are drawn from their saved output.
REDRAWN = ("footing", "stability", "verification", "large-strain")
#: 6 x 6 nodes, 10 steps to a settlement of 0.1 B (as tests/test_footing_pictures.py).
TINY = ("discretisation.x=[[1.0, 2], [10.0, 3, 3.0]]",
        "discretisation.y=[[9.0, 3, 0.3333333333333333], [10.0, 2]]", "time.steps=10",
        "time.end=10")
UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture
def drawn(monkeypatch):
    """The figures saved through :func:`soilwater.studies.harness.figures.save`, as
    ``(path name, problems)``: each checked before it is written and closed."""
    saved = []
    original = figures.save

    def check_then_save(fig, path, dpi=figures.DPI):
        saved.append((path.name, problems(fig, dpi)))
        return original(fig, path, dpi)
    monkeypatch.setattr(figures, "save", check_then_save)
    return saved


def problems(fig, dpi):
    """What keeps ``fig`` off a slide: its shape and size at ``dpi``, and each data axes
    or colour bar without a label carrying a unit."""
    found = []
    width, height = fig.get_size_inches() * dpi
    if not 1.6 <= width / height <= 1.9:
        found.append(f"aspect {width / height:.2f}")
    if width < 1280:
        found.append(f"{width:.0f} px wide")
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        if hasattr(ax, "_colorbar"):
            bar = ax._colorbar
            text = (ax.get_ylabel() if bar.orientation == "vertical" else ax.get_xlabel())
            if not UNIT.search(text):
                found.append(f"colour bar label {text!r}")
            continue
        if not (ax.lines or ax.collections or ax.images or ax.patches):
            continue
        for axis in "xy":
            text = _label(fig, ax, axis)
            if not UNIT.search(text):
                found.append(f"{ax.get_title()!r}: {axis} label {text!r}")
    return found


def _label(fig, ax, axis):
    """The label of ``ax``'s ``axis``: its own, else that of an axes it shares the axis
    with, else the figure's common one."""
    shared = ax.get_shared_x_axes() if axis == "x" else ax.get_shared_y_axes()
    for other in [ax, *shared.get_siblings(ax)]:
        text = other.get_xlabel() if axis == "x" else other.get_ylabel()
        if text:
            return text
    return fig.get_supxlabel() if axis == "x" else fig.get_supylabel()


@pytest.mark.parametrize("name", REDRAWN)
def test_saved_outputs_redraw_as_slides(name, drawn, tmp_path):
    saved = load(ROOT / "reports", name)
    if saved is None:
        pytest.skip(f"no saved output of {name} under reports/studies")
    paths = STUDIES[name].load().figures(tmp_path, saved.data)
    assert all(path.stat().st_size > 0 for path in paths)
    assert {p.name for p in paths} - {"infsup.png"} == {n for n, _ in drawn}
    assert {n: p for n, p in drawn if p} == {}


@pytest.fixture(scope="module")
def tiny():
    case = load_case("strip-footing", list(TINY))
    return [efg_solve(case, progress=False), fem_solve(case, "fem-th", progress=False)]


def test_footing_pictures_are_slides(tiny, drawn, tmp_path):
    pictures.deformed_figure(tiny, tmp_path / "deformed.png")
    pictures.pore_pressure_figure(tiny, tmp_path / "pore.png")
    assert [n for n, _ in drawn] == ["deformed.png", "pore.png"]
    assert {n: p for n, p in drawn if p} == {}


def test_save_writes_whole_stamps_a_quick_report_and_closes(tmp_path, monkeypatch):
    """A quick report's figure carries its label; the file appears only once written,
    and the figure is closed either way."""
    import matplotlib.pyplot as plt

    monkeypatch.setenv(quick.VARIABLE, "1")
    with figures.style():
        fig, ax = figures.slide()
        ax.plot([0, 1], [0, 1])
        path = figures.save(fig, tmp_path / "quick.png")
    assert path.stat().st_size > 0 and not plt.fignum_exists(fig.number)
    assert any(t.get_text() == quick.LABEL for t in fig.texts)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quick.png"]
    monkeypatch.delenv(quick.VARIABLE)

    def fail(*args, **kwargs):
        raise OSError("disk full")
    fig, _ = figures.slide()
    monkeypatch.setattr(type(fig), "savefig", fail)
    with pytest.raises(OSError, match="disk full"):
        figures.save(fig, tmp_path / "failed.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quick.png"]
    assert not plt.fignum_exists(fig.number)
    assert not any(t.get_text() == quick.LABEL for t in fig.texts)
