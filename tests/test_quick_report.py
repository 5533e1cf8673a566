"""``soilwater report --quick``: a smoke run of the quick report on its study without
solver runs (the sweeps' progress is tested with the runner), into its own folder."""

import os
import subprocess
import sys

import pandas as pd

from soilwater.studies.harness.quick import LABEL
from soilwater.studies.registry import STUDIES

SMOKE = ("material",)


def test_the_quick_report_writes_its_own_labelled_folder(tmp_path):
    out, cache = tmp_path / "quick", tmp_path / "cache"
    env = {**os.environ, "SOILWATER_CACHE": str(cache)}
    env.pop("SOILWATER_QUICK", None)
    done = subprocess.run([sys.executable, "-m", "soilwater.cli", "report", "--quick",
                           "--out", str(out), "--only", ",".join(SMOKE)],
                          capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    text = (out / "REPORT.md").read_text()
    assert text.startswith("# soilwater report (quick)")
    assert text.count(LABEL) == 1 + len(STUDIES) - text.count("has not been run yet")
    assert "Stale" not in text
    assert all(f"Study `{name}` has not been run yet" in text
               for name in STUDIES if name not in SMOKE)
    for name in SMOKE:
        assert (out / "studies" / f"{name}.pkl").exists()
    assert {p.name for p in (out / "figures").iterdir()} == {"stress_paths_driver.png"}
    for table in (out / "tables").glob("*.csv"):
        assert not pd.read_csv(table).select_dtypes("number").isna().all().any(), table
    assert done.stderr.splitlines()[0] == "report: study 1/1 material; 1 study never made here"
    again = subprocess.run([sys.executable, "-m", "soilwater.cli", "report", "--out",
                            str(out), "--only", "material"],
                           capture_output=True, text=True, env=env, cwd=tmp_path)
    assert again.returncode == 2
    assert again.stderr.strip().splitlines() == [
        f"soilwater: error: {out} holds a quick report (material): write the "
        "full one elsewhere (--out DIR; default reports)"]
