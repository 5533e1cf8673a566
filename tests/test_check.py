"""Regression against reports/reference/: passes on main, fails readably on a change."""

import shutil

import pandas as pd

from soilwater.studies.check import REFERENCE, check
from soilwater.cli import main


def test_check_passes_on_main(capsys):
    assert main(["check"]) == 0
    out = capsys.readouterr().out
    assert out.count(": ok") == 4


def test_a_reference_altered_by_1e_3_fails_with_a_readable_diff(tmp_path):
    folder = tmp_path / "reference"
    shutil.copytree(REFERENCE, folder)
    table = pd.read_csv(folder / "column_stability.csv")
    original = table.loc[1, "overshoot"]
    table.loc[1, "overshoot"] = original * (1 + 1e-3)
    table.to_csv(folder / "column_stability.csv", index=False)
    lines = check(folder, names=["column_stability"])["column_stability"]
    assert len(lines) == 1
    assert lines[0].startswith("row 1, overshoot: reference")
    assert f"{original:.6g}"[:6] in lines[0] and "allowed 0.0001 relative" in lines[0]


def test_past_the_onset_only_bounds_apply_and_before_it_everything_is_compared():
    """On the committed unconfined table: a 0.5 % change of fem-th's q fails on every row
    before its departure and on none after it; past the onset ERR need only be >= 0."""
    from soilwater.studies.check import TABLES, compare

    _, rtol, atol, branch = TABLES["unconfined_err"]
    ref = pd.read_csv(REFERENCE / "unconfined_err.csv")
    th = ref.run == "fem-th"
    departed = th & (ref.err > branch["departure"][1]).groupby(ref.run).cummax()
    assert departed.any() and (th & ~departed).any()
    got = ref.copy()
    got.loc[th, "q"] *= 1.005
    lines = compare(ref, got, rtol, atol, branch)
    assert len(lines) == (th & ~departed).sum() and all(", q:" in line for line in lines)
    got = ref.copy()
    after = (ref.regime == "after") & ~th
    got.loc[after, "err"] = 0.5                      # another branch: allowed
    assert compare(ref, got, rtol, atol, branch) == []
    got.loc[after.idxmax(), "err"] = -0.5            # not physical: caught
    assert len(compare(ref, got, rtol, atol, branch)) == 1
