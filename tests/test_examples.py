"""Every gallery example runs as a plain script and prints what its prose says."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
SCRIPTS = sorted(EXAMPLES.glob("plot_*.py"))


def rows(stdout, columns):
    """``{label: [floats]}`` of the printed table lines ending in ``columns`` numbers."""
    table = {}
    for line in stdout.splitlines():
        words = line.split()
        if words[:1] in (["EFG"], ["FEM"]) and len(words) > columns:
            table[" ".join(words[:-columns])] = [float(w) for w in words[-columns:]]
    return table


def material_driver(out):
    gap = next(line for line in out.splitlines() if line.startswith("driver vs closed form"))
    assert float(gap.split("=")[-1]) < 1e-8
    reached, critical = out.split("at eps_a = 0.2: ")[1].split("; critical state: ")
    assert [float(w.split("=")[-1]) for w in reached.split(",")] == pytest.approx(
        [float(w) for w in critical.split(",")], abs=1e-3)


def unconfined_compression(out):
    compression = rows(out, 3)  # path_error, err_mean, err_max
    assert len(compression) == 5
    for label in ("EFG delaunay none", "EFG delaunay vci", "EFG squares vci",
                  "FEM taylor-hood"):
        assert compression[label][0] < 0.02, label
    assert compression["EFG squares none"][0] > 1.0
    assert compression["EFG delaunay vci"][1] < 1e-4  # ERR: uniform only with VCI
    assert compression["EFG delaunay none"][1] > 0.1


def soil_column(out):
    ratio = next(line for line in out.splitlines() if line.startswith("h^2 / (c_v dt)"))
    assert 20 < float(ratio.split("=")[-1]) < 40
    column = rows(out, 2)  # overshoot, oscillation
    efg = [column[f"EFG {w}"] for w in ("Q/Q", "E-A/E-A", "E-A/E-B")]
    fem = column["FEM taylor-hood"]
    assert len(column) == 5
    assert all(o < fem[0] and osc > fem[1] for o, osc in efg)
    assert min(o for o, _ in efg) == efg[2][0]
    assert min(osc for _, osc in efg) < efg[2][1]  # E-A/E-B: not the least wiggly


CLAIMS = {"plot_01_material_driver.py": material_driver,
          "plot_02_unconfined_compression.py": unconfined_compression,
          "plot_03_soil_column.py": soil_column}


def test_every_example_has_its_claims_checked():
    assert [script.name for script in SCRIPTS] == sorted(CLAIMS)


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda script: script.stem)
def test_the_example_runs_and_reproduces_its_claims(script, tmp_path):
    # The working directory keeps the repository clean; Agg draws without a display.
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, timeout=300,
                          check=False, env={**os.environ, "MPLBACKEND": "Agg"},
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    CLAIMS[script.name](done.stdout)
