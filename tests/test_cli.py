"""The ``soilwater`` command: output files, one-line errors, nothing written on failure,
nothing deleted that soilwater did not write."""

import errno
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from soilwater.cli import Interrupted, main


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
    strain = [] if "--strain" in args else ["--strain", "0.1"]   # an option is given once
    base = ["path", "--test", "isotropic", *strain, "--out", str(out)]
    cmd = [sys.executable, "-m", "soilwater.cli"] + base + args
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error:") and word in lines[0]
    assert not out.exists() and list(tmp_path.iterdir()) == [tmp_path / "clay.toml"]


def test_list_names_every_builtin_case_with_a_description(capsys):
    from soilwater.case.loader import builtin_cases

    assert main(["list"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == list(builtin_cases())
    assert all(len(line.split()) > 3 for line in lines)


def test_show_applies_overrides(capsys):
    assert main(["show", "soil-column", "--set", "discretisation.ny=41"]) == 0
    assert "# 123 nodes" in capsys.readouterr().out


def test_show_names_the_efg_configuration_in_force(capsys):
    assert main(["show", "terzaghi"]) == 0
    assert "runs the recommended EFG configuration" in capsys.readouterr().out
    assert main(["show", "terzaghi", "--set", "efg.integration=paper"]) == 0
    assert ("custom EFG configuration: integration = paper (recommended: gauss)"
            in capsys.readouterr().out)
    assert main(["show", "terzaghi", "--set", "efg.integration=paper", "--set",
                 "efg.essential=penalty", "--set", "efg.stabilisation=none"]) == 0
    assert "runs the paper EFG configuration" in capsys.readouterr().out


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
        (Path(__file__).parents[1] / "src" / "soilwater" / "case" / "builtin"
         / "terzaghi.toml").read_text()
        .replace("end = 10.0", "end = 10.0\nviscosity = 1e-3"))
    proc = subprocess.run([sys.executable, "-m", "soilwater.cli"] + args, cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0], proc.stderr


def _cli(args, cwd, **kwargs):
    """Run ``soilwater ARGS`` in a real process."""
    return subprocess.run([sys.executable, "-m", "soilwater.cli", *args], cwd=cwd,
                          capture_output=True, text=True, **kwargs)


def _contents(folder):
    """Every file and folder under ``folder`` (hidden ones too), with file contents."""
    return {p.relative_to(folder): p.read_bytes() if p.is_file() else None
            for p in sorted(Path(folder).rglob("*"))}


def test_run_into_the_current_folder_is_refused_and_touches_nothing(tmp_path):
    (tmp_path / "notes.txt").write_text("my notes")
    proc = _cli(["run", "unconfined-compression", "--method", "efg", "--out", "."],
                tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error:")
    assert str(tmp_path.resolve()) in lines[0] and "Traceback" not in proc.stderr
    assert _contents(tmp_path) == {Path("notes.txt"): b"my notes"}


@pytest.fixture
def refusing(tmp_path, monkeypatch):
    """A home folder, a working folder holding notes.txt, a data folder and a link to
    the working folder's parent; the solvers fail the test if they are ever called."""
    from soilwater.methods import METHODS

    home, work, data = tmp_path / "home", tmp_path / "a" / "work", tmp_path / "data"
    for folder in (home, work, data):
        folder.mkdir(parents=True)
    (work / "notes.txt").write_text("my notes")
    (data / "x.csv").write_text("time\n1.0\n")
    (work / "up").symlink_to("..")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    for method in METHODS:
        monkeypatch.setitem(METHODS, method, lambda *a, **k: pytest.fail("solver called"))
    return tmp_path.resolve()


@pytest.mark.parametrize("out,named,word", [
    ("..", "a", "current folder"),
    ("up", "a", "current folder"),
    ("/", "/", "current folder"),
    ("HOME", "home", "home folder"),
    ("notes.txt", "a/work/notes.txt", "is a file"),
    ("../../data", "data", "did not write"),
])
def test_run_refuses_folders_it_did_not_write_before_solving(refusing, capsys, out, named,
                                                               word):
    before = _contents(refusing)
    out = str(refusing / "home") if out == "HOME" else out
    assert main(["run", "patch-test", "--method", "efg", "--out", out]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error:") and word in lines[0]
    assert str(refusing / named) in lines[0]  # "/" stays "/"
    assert _contents(refusing) == before


def test_a_second_run_replaces_the_first_result(tmp_path, monkeypatch):
    from soilwater.targets import MARKER

    monkeypatch.chdir(tmp_path)
    out = tmp_path / "run"
    out.mkdir()  # an empty folder is accepted
    args = ["run", "patch-test", "--method", "efg", "--out", str(out)]
    assert main(args) == 0 and (out / MARKER).is_file()
    assert main(args + ["--set", "discretisation.nx=5"]) == 0
    assert (out / MARKER).is_file() and '"nx": 5' in (out / "summary.json").read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


def test_run_refuses_a_previous_result_holding_the_users_files(refusing, capsys):
    from soilwater.targets import MARKER

    out = refusing / "runs" / "stab"
    out.mkdir(parents=True)
    (out / MARKER).write_text('{"written_by": "soilwater", "files": ["summary.json"]}\n')
    (out / "summary.json").write_text("{}")
    (out / "pw.png").write_bytes(b"the user's figure")
    before = _contents(refusing)
    assert main(["run", "patch-test", "--method", "efg", "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(out) in lines[0]
    assert "1 entry soilwater did not write (pw.png)" in lines[0]
    assert _contents(refusing) == before


def _handles_sigterm(pid):
    """Whether process ``pid`` has installed a SIGTERM handler (Linux /proc)."""
    status = Path(f"/proc/{pid}/status").read_text()
    caught = int(status.split("SigCgt:")[1].split()[0], 16)
    return bool(caught >> (signal.SIGTERM - 1) & 1)


def test_a_signal_swallowed_by_a_library_is_still_one_line(tmp_path, monkeypatch, capsys):
    """numba's compiler, called back through ctypes, swallows the interruption and then
    fails with its own RuntimeError (seen on a fresh clone, SIGTERM while compiling):
    still the interruption's one line and status, no traceback."""
    import os

    from soilwater.methods import METHODS

    def library(case, progress=True):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)
        except KeyboardInterrupt:
            pass                                  # what the ctypes callback did
        raise RuntimeError("no compiled object yet")

    monkeypatch.setitem(METHODS, "efg", library)
    status = main(["run", "patch-test", "--method", "efg", "--out", str(tmp_path / "r")])
    assert status == 143
    assert capsys.readouterr().err.strip().splitlines() == [
        "soilwater: interrupted (SIGTERM): no half-written output was left"]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
def test_sigterm_during_a_run_is_one_line_and_leaves_nothing(tmp_path):
    cmd = [sys.executable, "-m", "soilwater.cli", "run", "unconfined-compression",
           "--method", "efg", "--out", "run", "--set", "time.steps=400", "--quiet"]  # ~30 s
    proc = subprocess.Popen(cmd, cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while not _handles_sigterm(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(2.5)  # past the imports (about 1 s) and the case set-up: solving
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert err.strip().splitlines() == [
        "soilwater: interrupted (SIGTERM): no half-written output was left"]
    assert list(tmp_path.iterdir()) == []


def test_stdout_closed_early_is_silent(tmp_path):
    cmd = [sys.executable, "-m", "soilwater.cli", "show", "soil-column"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    proc.stdout.close()  # before soilwater writes: every write meets a closed pipe
    err = proc.stderr.read()
    assert proc.wait(timeout=30) == 141 and err == ""


@pytest.mark.parametrize("error,status,text", [
    (OSError(errno.ENOSPC, "No space left on device", "fields_0000.vtu"), 2,
     r"soilwater: error: fields_0000\.vtu: No space left on device"),
    (PermissionError(errno.EACCES, "Permission denied"), 2,  # names no file: given one
     r"soilwater: error: .*/run/fields_0000\.vtu: Permission denied"),  # the result's
    (Interrupted(signal.SIGTERM), 143,
     r"soilwater: interrupted \(SIGTERM\): no half-written output was left"),
])
def test_a_failing_write_is_one_line_and_keeps_the_previous_result(
        tmp_path, monkeypatch, capsys, error, status, text):
    import meshio

    monkeypatch.chdir(tmp_path)
    args = ["run", "patch-test", "--method", "efg", "--out", "run", "--quiet"]
    assert main(args) == 0
    before = _contents(tmp_path)
    capsys.readouterr()

    def fail(*args, **kwargs):
        raise error

    monkeypatch.setattr(meshio, "write", fail)
    assert main(args) == status
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and re.fullmatch(text, lines[0]), lines
    assert _contents(tmp_path) == before


def test_a_failing_first_write_leaves_no_folder(tmp_path, monkeypatch, capsys):
    import meshio

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", args[0])

    monkeypatch.setattr(meshio, "write", full)
    out = tmp_path / "run"
    assert main(["run", "patch-test", "--method", "efg", "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "No space left on device" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_path_refuses_a_folder_as_its_csv_file(tmp_path, capsys):
    (tmp_path / "old.csv").write_text("kept")
    assert main(["path", "table1", "--test", "oedometer", "--strain", "0.05",
                 "--out", str(tmp_path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(tmp_path) in lines[0] and "is a folder" in lines[0]
    assert _contents(tmp_path) == {Path("old.csv"): b"kept"}


_PATH = ["path", "table1", "--test", "oedometer", "--strain", "0.05", "--points", "5"]


def test_path_refuses_a_file_it_did_not_write_and_replaces_its_own(tmp_path, capsys):
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes")
    assert main(_PATH + ["--out", str(notes)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(notes) in lines[0] and "did not write" in lines[0]
    assert notes.read_text() == "my notes"
    out = tmp_path / "path.csv"
    assert main(_PATH + ["--out", str(out)]) == 0
    assert main(_PATH[:5] + ["0.1"] + _PATH[6:] + ["--out", str(out)]) == 0  # replaced
    assert pd.read_csv(out).eps_a.iloc[-1] == pytest.approx(0.1)


def test_path_writes_through_no_symbolic_link(tmp_path, capsys):
    target = tmp_path / "target.csv"
    target.write_text("kept")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    for out in (link, Path("/dev/stdout")):
        assert main(_PATH + ["--out", str(out)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and "symbolic link" in lines[0] and str(out) in lines[0]
    assert link.is_symlink() and target.read_text() == "kept"


def test_an_out_under_a_file_fails_before_solving(tmp_path, monkeypatch, capsys):
    from soilwater.methods import METHODS

    (tmp_path / "mydata.txt").write_text("mine")
    monkeypatch.setitem(METHODS, "efg", lambda *a, **k: pytest.fail("solver called"))
    for args in (["run", "strip-footing", "--method", "efg"], _PATH):
        assert main(args + ["--out", str(tmp_path / "mydata.txt" / "sub")]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and f"{tmp_path / 'mydata.txt'} is a file" in lines[0]
    assert _contents(tmp_path) == {Path("mydata.txt"): b"mine"}


def test_result_files_take_the_users_umask(tmp_path):
    previous = os.umask(0o027)
    try:
        assert main(["run", "patch-test", "--method", "efg", "--quiet",
                     "--out", str(tmp_path / "run")]) == 0
        assert main(_PATH + ["--out", str(tmp_path / "path.csv")]) == 0
    finally:
        os.umask(previous)
    modes = {p.name: p.stat().st_mode & 0o777 for p in tmp_path.rglob("*")}
    assert modes["run"] == 0o750 and modes["history.csv"] == 0o640
    assert modes["path.csv"] == 0o640


def test_a_full_disk_names_the_file(tmp_path, monkeypatch, capsys):
    import pandas

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")  # as a write reports it

    monkeypatch.setattr(pandas.DataFrame, "to_csv", full)
    out = tmp_path / "path.csv"
    assert main(_PATH + ["--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"soilwater: error: {out}: No space left on device"]
    assert list(tmp_path.iterdir()) == []


def test_progress_without_a_terminal_is_plain_lines_and_quiet_silences_it(tmp_path,
                                                                         capsys):
    args = ["run", "terzaghi", "--method", "efg", "--set", "time.steps=40"]
    assert main(args + ["--out", str(tmp_path / "a")]) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert 20 <= len(lines) <= 22 and lines[0].startswith("efg terzaghi: step 1/40, t = ")
    assert re.fullmatch(r"efg terzaghi: step 40/40, t = \S+ s, \d+ Newton iterations, 0 "
                        r"cut-backs, \d+ s elapsed, about 0 s left", lines[-1]), lines[-1]
    assert main(args + ["--out", str(tmp_path / "b"), "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_a_second_run_on_the_same_out_is_refused_while_the_first_writes_it(tmp_path,
                                                                           capsys):
    """Two runs started on one --out: the second refuses in one line naming the first's
    process, and the first writes its result."""
    out = tmp_path / "conc"
    first = subprocess.Popen([sys.executable, "-m", "soilwater.cli", "run", "terzaghi",
                              "--method", "fem-th", "--out", str(out), "--quiet",
                              "--set", "time.steps=400", "--set", "time.end=1.0"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lock = tmp_path / ".conc.lock"
    deadline = time.monotonic() + 60
    while not (lock.exists() and lock.read_text().strip()) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert first.poll() is None, first.communicate()
    assert main(["run", "terzaghi", "--method", "efg", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"soilwater: error: --out {out} is being written by another soilwater "
                   f"run (process {first.pid}, lock {lock}); wait for it to end, or "
                   "choose another --out"]
    stdout, stderr = first.communicate(timeout=300)
    assert first.returncode == 0, stderr
    assert stdout.startswith(f"wrote {out}") and (out / "summary.json").is_file()
    assert not lock.exists()


@pytest.mark.parametrize("args, words", [
    (["run", "terzaghi", "--method", "efg", "--out", "a", "--out", "b"],
     "--out is given twice: give it once"),
    (["path", "table1", "--test", "isotropic", "--strain", "0.1", "--ocr", "inf",
      "--out", "p.csv"], "'inf' is not a finite number"),
    (["path", "table1", "--test", "isotropic", "--strain", "0.1", "--ocr", "1e300",
      "--out", "p.csv"], "1e300 is past 10000"),
    (["path", "table1", "--test", "isotropic", "--strain", "nan", "--out", "p.csv"],
     "'nan' is not a finite number"),
    (["path", "table1", "--test", "isotropic", "--strain", "0.1", "--points", "100000000",
      "--out", "p.csv"], "must be from 1 to 1000000"),
    (["infsup", "--methods", "", "--sizes", "3", "--out", "i.csv"],
     "give one or more methods"),
    (["infsup", "--methods", "fem-th", "--sizes", "3,3", "--out", "i.csv"],
     "--sizes names 3 twice"),
    (["infsup", "--methods", "fem-th,fem-th", "--sizes", "3", "--out", "i.csv"],
     "--methods names fem-th twice"),
    (["infsup", "--methods", "fem-th", "--sizes", "3", "--set", "time.end=1",
      "--out", "i.csv"], "infsup takes EFG settings only")])
def test_options_given_twice_or_out_of_range_are_refused_before_any_work(
        tmp_path, monkeypatch, capsys, args, words):
    """argparse's refusals exit with status 2 (SystemExit), soilwater's return it."""
    monkeypatch.chdir(tmp_path)
    try:
        status = main(args)
    except SystemExit as exit:
        status = exit.code
    assert status == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert words in err[-1] and list(tmp_path.iterdir()) == []
