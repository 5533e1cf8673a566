"""Regression against reports/reference/: passes on main, fails readably on a change."""

import shutil

import pandas as pd

from comparisons.check import REFERENCE, check
from comparisons.cli import main


def test_check_passes_on_main(capsys):
    assert main(["check"]) == 0
    out = capsys.readouterr().out
    assert out.count(": ok") == 4


def test_a_reference_altered_by_1e_3_fails_with_a_readable_diff(tmp_path):
    folder = tmp_path / "reference"
    shutil.copytree(REFERENCE, folder)
    table = pd.read_csv(folder / "column_stability.csv")
    original = table.loc[1, "overshoot_first"]
    table.loc[1, "overshoot_first"] = original * (1 + 1e-3)
    table.to_csv(folder / "column_stability.csv", index=False)
    lines = check(folder, names=["column_stability"])["column_stability"]
    assert len(lines) == 1
    assert lines[0].startswith("row 1, overshoot_first: reference")
    assert f"{original:.6g}"[:6] in lines[0] and "allowed 0.0001 relative" in lines[0]
