"""The ``soilwater`` command: output files, one-line errors, nothing written on failure."""

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from comparisons.cli import main


def test_path_writes_the_documented_columns(tmp_path):
    out = tmp_path / "path.csv"
    assert main(["path", "table1", "--test", "undrained-plane-strain", "--strain", "0.2",
                 "--model", "modified", "--points", "40", "--out", str(out)]) == 0
    table = pd.read_csv(out)
    assert list(table.columns) == ["step", "eps_a", "eps_v", "p", "q", "pc"]
    assert len(table) == 41 and table.eps_a.iloc[-1] == pytest.approx(0.2)
    assert (table.p <= 3.0 + 1e-12).all() and table.q.iloc[-1] > 0


def test_path_reads_a_toml_material(tmp_path):
    toml = tmp_path / "clay.toml"
    toml.write_text('[material]\npreset = "table1"\nmodel = "modified"\nocr = 2.0\n')
    out = tmp_path / "path.csv"
    assert main(["path", str(toml), "--test", "oedometer", "--strain", "0.05",
                 "--out", str(out)]) == 0
    assert pd.read_csv(out).pc.iloc[0] == pytest.approx(6.0)


@pytest.mark.parametrize("args,word", [
    (["table1", "--ocr", "0.5"], "ocr"),
    (["clay.toml"], "lambda"),
    (["table9"], "table9"),
    (["table1", "--strain", "-0.1"], "strain"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, args, word):
    (tmp_path / "clay.toml").write_text("[material]\nlambda = 0.02\nkappa = 0.04\n"
                                        "M = 1.2\nnu = 0.3\ne0 = 1.0\np0 = 100.0\n")
    out = tmp_path / "out.csv"
    base = ["path", "--test", "isotropic", "--strain", "0.1", "--out", str(out)]
    cmd = [sys.executable, "-m", "comparisons.cli"] + base + args  # the last flag wins
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error:") and word in lines[0]
    assert not out.exists() and list(tmp_path.iterdir()) == [tmp_path / "clay.toml"]


def test_list_names_every_builtin_case_with_a_description(capsys):
    from soil.problems import builtin_cases

    assert main(["list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == list(builtin_cases())
    assert all(len(line.split()) > 3 for line in lines)


def test_show_applies_overrides(capsys):
    assert main(["show", "soil-column", "--set", "discretisation.ny=41"]) == 0
    assert "# 123 nodes" in capsys.readouterr().out


@pytest.mark.parametrize("args,word", [
    (["show", "unconfined-compresion"], "unconfined-compresion"),
    (["show", "case.toml"], "viscosity"),
    (["show", "soil-column", "--set", "material.permeability=-1e-5"], "permeability"),
    (["show", "soil-column", "--set", "material.nu=0.5"], "nu"),
    (["show", "soil-column", "--set", "material.p0=0"], "p0"),
    (["show", "soil-column", "--set", "material.lambda=0.01"], "lambda"),
])
def test_bad_case_input_is_one_line(tmp_path, args, word):
    (tmp_path / "case.toml").write_text(
        (Path(__file__).parents[1] / "cases" / "terzaghi.toml").read_text()
        .replace("end = 10.0", "end = 10.0\nviscosity = 1e-3"))
    proc = subprocess.run([sys.executable, "-m", "comparisons.cli"] + args, cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0], proc.stderr
