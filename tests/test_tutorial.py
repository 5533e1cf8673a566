"""docs/tutorial.py runs as a plain script and prints what its prose says."""

import os
import subprocess
import sys
from pathlib import Path

TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial.py"


def rows(stdout, columns):
    """``{label: [floats]}`` of the printed table lines ending in ``columns`` numbers."""
    table = {}
    for line in stdout.splitlines():
        words = line.split()
        if words[:1] in (["EFG"], ["FEM"]) and len(words) > columns:
            table[" ".join(words[:-columns])] = [float(w) for w in words[-columns:]]
    return table


def test_the_tutorial_runs_and_reproduces_its_claims(tmp_path):
    # TMPDIR puts the figures under tmp_path; the working directory keeps the repo clean.
    done = subprocess.run([sys.executable, str(TUTORIAL)], cwd=tmp_path, timeout=300,
                          check=False, env={**os.environ, "TMPDIR": str(tmp_path)},
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    gap = next(line for line in out.splitlines() if line.startswith("driver vs closed form"))
    assert float(gap.split("=")[-1]) < 1e-8

    part2, part3 = out.split("h^2 / (c_v dt)")
    compression = rows(part2, 3)  # path_error, err_mean, err_max
    assert len(compression) == 5
    for label in ("EFG delaunay none", "EFG delaunay vci", "EFG squares vci",
                  "FEM taylor-hood"):
        assert compression[label][0] < 0.02, label
    assert compression["EFG squares none"][0] > 1.0
    assert compression["EFG delaunay vci"][1] < 1e-4  # ERR: uniform only with VCI
    assert compression["EFG delaunay none"][1] > 0.1

    column = rows(part3, 2)  # overshoot, oscillation
    efg = [column[f"EFG {w}"] for w in ("Q/Q", "E-A/E-A", "E-A/E-B")]
    fem = column["FEM taylor-hood"]
    assert len(column) == 5
    assert all(o < fem[0] and osc > fem[1] for o, osc in efg)
    assert min(o for o, _ in efg) == efg[2][0]
    assert min(osc for _, osc in efg) < efg[2][1]  # E-A/E-B: not the least wiggly

    assert {p.name for p in tmp_path.glob("soilwater-tutorial-*/*.png")} == {
        "unconfined_compression.png", "soil_column_first_step.png"}
