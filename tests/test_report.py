"""``soilwater report``: one shape for every study, ``--only``, stale sections, and the
studies kept apart from the library and from each other.

The report tests run on a fake registry of two trivial studies (each writes a table and
counts its runs); no real study runs here.
"""

import ast
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import soilwater
from soilwater.cli import main
from soilwater.errors import SoilwaterError
from soilwater.studies import registry
from soilwater.studies import report
from soilwater.studies.harness import sources
from soilwater.studies.harness import study as store

STUDIES = Path(soilwater.__file__).parent / "studies"
TRIVIAL = '''
import pandas as pd

from soilwater.studies.harness import tables

NAME = "{name}"
RUNS = []


def run(root, inputs):
    RUNS.append(root)
    table = pd.DataFrame({{"x": [1.0, 2.0]}})
    tables.write(table, root / "tables" / "{name}")
    return {{"value": len(RUNS)}}


def section(data):
    return ["## Study {name}", "", f"{name} value {{data['value']}}", ""]
'''


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """Two trivial studies, ``alpha`` and ``beta``, each in its own folder; returns the
    report root."""
    for name in ("alpha", "beta"):
        folder = tmp_path / "fake" / f"fake_{name}"
        folder.mkdir(parents=True)
        (folder / "__init__.py").write_text("")
        (folder / "report.py").write_text(TRIVIAL.format(name=name))
    monkeypatch.syspath_prepend(str(tmp_path / "fake"))
    monkeypatch.setattr(registry, "STUDIES", {
        name: store.Study(name, f"fake_{name}.report") for name in ("alpha", "beta")})
    yield tmp_path / "reports"
    for name in ("alpha", "beta"):
        sys.modules.pop(f"fake_{name}.report", None)
        sys.modules.pop(f"fake_{name}", None)


def runs(name):
    return sys.modules[f"fake_{name}.report"].RUNS


def test_a_full_report_runs_every_study_and_records_its_code(fake):
    written = report.make_report(fake)
    text = (fake / "REPORT.md").read_text()
    assert "alpha value 1" in text and "beta value 1" in text
    assert (fake / "tables" / "alpha.csv").exists() and (fake / "tables" / "beta.md").exists()
    assert fake / "REPORT.md" in written
    meta = store.load(fake, "alpha").meta
    assert meta["solvers"] == []
    modules = store.dependencies(registry.STUDIES["alpha"], registry.STUDIES, [])
    assert meta["modules"] == modules and meta["code"] == sources.digest(modules)
    assert "case/model.py" in modules and "efg/solver.py" not in modules
    assert any(p.endswith("fake_alpha/report.py") for p in modules)
    assert f"made from code `{meta['code'][:7]}`" in text
    assert (f"Assembled by `soilwater report --out {fake}` on " in text
            and f"from source `{sources.package_hash()}`" in text)
    assert "Stale" not in text


def test_only_reruns_the_named_study_and_keeps_the_others_output(fake):
    report.make_report(fake)
    beta = ((fake / "studies" / "beta.pkl").read_bytes(),
            (fake / "studies" / "beta.json").read_text())
    report.make_report(fake, only="alpha")
    assert len(runs("alpha")) == 2 and len(runs("beta")) == 1
    assert ((fake / "studies" / "beta.pkl").read_bytes(),
            (fake / "studies" / "beta.json").read_text()) == beta
    text = (fake / "REPORT.md").read_text()
    assert "alpha value 2" in text and "beta value 1" in text
    assert "Stale" not in text


def test_a_changed_source_marks_the_section_stale_and_a_comment_does_not(fake):
    report.make_report(fake)
    source = Path(sys.modules["fake_beta.report"].__file__)
    source.write_text(source.read_text() + "\n# an edit\n")
    report.make_report(fake, only="alpha")
    assert "**Stale**" not in (fake / "REPORT.md").read_text()
    source.write_text(source.read_text() + "\nEDITED = 1\n")
    report.make_report(fake, only="alpha")
    text = (fake / "REPORT.md").read_text()
    beta = text[text.index("## Study beta"):]
    assert "**Stale**" in beta and f"soilwater report --only beta --out {fake}`" in beta
    assert "fake_beta/report.py" in beta
    assert "**Stale**" not in text[:text.index("## Study beta")]


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A copy of the package's sources that the source hashes read instead of the real
    one (the studies still import the real package)."""
    copy = tmp_path / "package"
    shutil.copytree(sources.PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(sources, "PACKAGE", copy)
    return copy


def edit(path):
    """A change of code (not of a comment) at the end of ``path``."""
    path.write_text(path.read_text() + "\n_EDITED = 1\n")


def test_a_change_to_a_solver_marks_stale_only_the_sections_that_used_it(fake, package):
    alpha = Path(registry.STUDIES["alpha"].load().__file__)
    alpha.write_text(alpha.read_text() + "\nimport soilwater.efg.weights\n")
    report.make_report(fake)
    assert store.load(fake, "alpha").meta["solvers"] == ["efg"]
    edit(package / "fem" / "solver.py")
    report.make_report(fake, only="beta")
    assert "**Stale**" not in (fake / "REPORT.md").read_text()
    edit(package / "efg" / "weights.py")
    report.make_report(fake, only="beta")
    text = (fake / "REPORT.md").read_text()
    assert "**Stale**" in text[:text.index("## Study beta")]
    assert "`efg/weights.py`" in text[:text.index("## Study beta")]
    assert "**Stale**" not in text[text.index("## Study beta"):]
    edit(package / "case" / "model.py")
    report.make_report(fake, only="alpha")
    text = (fake / "REPORT.md").read_text()
    assert "**Stale**" in text[text.index("## Study beta"):]
    assert "**Stale**" not in text[:text.index("## Study beta")]


def test_a_study_not_run_yet_says_so(fake):
    report.make_report(fake, only="beta")
    text = (fake / "REPORT.md").read_text()
    assert "beta value 1" in text
    assert "Study `alpha` has not been run yet" in text


def test_unknown_studies_are_refused_in_one_line(fake, capsys):
    with pytest.raises(SoilwaterError, match="unknown study gamma") as err:
        report.make_report(fake, only="alpha,gamma")
    assert "\n" not in str(err.value) and "alpha, beta" in str(err.value)
    assert main(["report", "--out", str(fake), "--only", "gamma"]) == 2
    out = capsys.readouterr().err.strip()
    assert len(out.splitlines()) == 1 and "use one or more of alpha, beta" in out
    assert not (fake / "studies").exists()


def test_the_registry_names_each_study_once_with_its_interface():
    for name, study in registry.STUDIES.items():
        module = study.load()
        assert module.NAME == name
        assert callable(module.run) and callable(module.section)
        assert set(module.__dict__.get("NEEDS", ())) <= set(registry.STUDIES)


def _imports(path):
    """Absolute module names imported anywhere in a file (lazy imports included)."""
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.append(node.module)
    return names


def test_no_study_folder_imports_another():
    folders = {p.name for p in STUDIES.iterdir() if (p / "__init__.py").exists()}
    found = []
    for folder in sorted(folders - {"harness"}):
        for path in sorted((STUDIES / folder).rglob("*.py")):
            for name in _imports(path):
                parts = name.split(".")
                if (parts[:2] == ["soilwater", "studies"] and len(parts) > 2
                        and parts[2] in folders - {"harness", folder}):
                    found.append(f"{path.relative_to(STUDIES)} imports {name}")
    assert not found


def test_nothing_outside_the_studies_imports_them():
    """Only the CLI's ``report``, ``check`` and ``bench`` commands reach the studies, and
    lazily (inside the function of the command)."""
    package = STUDIES.parent
    found = []
    for path in sorted(package.rglob("*.py")):
        if path.relative_to(package).parts[0] == "studies":
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef) and path.name == "cli.py" and \
                    node.name in ("_report", "_check", "_bench"):
                node.body = []          # the commands' lazy imports are allowed
        for node in ast.walk(tree):
            modules = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                       [node.module] if isinstance(node, ast.ImportFrom) else [])
            found += [f"{path.relative_to(package)} imports {m}" for m in modules
                      if m and m.startswith("soilwater.studies")]
    assert not found


def test_importing_the_studies_leaves_the_matplotlib_backend_alone():
    modules = sorted(".".join(p.relative_to(STUDIES.parents[1]).with_suffix("").parts)
                     for p in STUDIES.rglob("*.py") if p.name != "__init__.py")
    code = textwrap.dedent(f"""
        import importlib, matplotlib
        matplotlib.use("svg")
        for name in {modules!r}:
            importlib.import_module(name)
        print(matplotlib.get_backend())
    """)
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True).stdout
    assert out.strip() == "svg"


def test_a_section_older_code_saved_asks_for_a_rerun_and_todays_errors_raise():
    """Output saved by older code that today's section cannot read gives one line
    naming the rerun, in place of a traceback; today's own output is never hidden."""
    from soilwater.studies.report import _readable

    def broken():
        raise KeyError("method")

    lines = _readable(broken, False, "## footing", "section `footing`",
                     "soilwater report --only footing")
    assert lines[0] == "## footing"
    assert "rerun `soilwater report --only footing`" in lines[2]
    assert _readable(lambda: ["ok"], False, "## x", "x", "x") == ["ok"]
    with pytest.raises(KeyError):
        _readable(broken, True, "## footing", "section `footing`", "footing")


def test_a_quick_report_is_labelled_and_never_mixed_with_a_full_one(fake, tmp_path,
                                                                   monkeypatch):
    """``SOILWATER_QUICK=1`` (``soilwater report --quick``) labels the page and each
    section; a folder holding one resolution's studies refuses the other's, in one line,
    without writing anything."""
    from soilwater.studies.harness.quick import LABEL, VARIABLE

    report.make_report(fake)
    full = (fake / "REPORT.md").read_text()
    monkeypatch.setenv(VARIABLE, "1")
    with pytest.raises(SoilwaterError, match="holds a full report") as err:
        report.make_report(fake)
    assert "\n" not in str(err.value) and "reports-quick" in str(err.value)
    assert (fake / "REPORT.md").read_text() == full and len(runs("alpha")) == 1
    quick = tmp_path / "quick"
    report.make_report(quick)
    text = (quick / "REPORT.md").read_text()
    assert text.startswith("# soilwater report (quick)")
    assert text.count(LABEL) == 1 + len(registry.STUDIES)
    assert store.load(quick, "alpha").meta["settings"]["quick"] is True
    monkeypatch.delenv(VARIABLE)
    with pytest.raises(SoilwaterError, match="holds a quick report"):
        report.make_report(quick)
    assert LABEL not in full


def test_redraw_draws_the_figures_from_the_saved_output_and_runs_nothing(fake):
    report.make_report(fake)
    module = sys.modules["fake_alpha.report"]
    drawn = []
    module.figures = lambda root, data: drawn.append((root, data["value"]))
    sys.modules["fake_beta.report"].figures = textwrap  # a submodule named figures
    report.make_report(fake, redraw=True)
    assert drawn == [(fake, 1)] and len(runs("alpha")) == len(runs("beta")) == 1
    assert "alpha value 1" in (fake / "REPORT.md").read_text()


def test_the_report_says_which_study_runs_and_the_time_left_in_plain_lines(fake, capsys):
    report.make_report(fake)
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "report: study 1/2 alpha; 2 studies never made here"
    report.make_report(fake)
    seconds = store.load(fake, "alpha").meta["seconds"] + store.load(fake, "beta").meta[
        "seconds"]
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("report: study 1/2 alpha; about ")
    assert err[0].endswith(" left by their last runs") and f"{round(seconds)} s" in err[0]


@pytest.mark.parametrize("setup, words", [
    (lambda d: (d / "REPORT.md").write_text("# My own notes\n"),
     "REPORT.md was not written by soilwater report"),
    (lambda d: (d / ".soilwater-output").write_text("{}\n"), "is a result of soilwater run"),
    (lambda d: (d / "data.csv").write_text("x\n1\n"), "is not a soilwater report")])
def test_a_report_never_writes_into_a_folder_soilwater_did_not_write(fake, tmp_path,
                                                                    capsys, setup, words):
    """``soilwater report --only alpha --out DIR`` refuses, before any study runs, a
    folder holding the user's REPORT.md, a run's result or other files, and changes
    nothing in it."""
    mine = tmp_path / "mine"
    mine.mkdir()
    setup(mine)
    before = {p.name: p.read_bytes() for p in mine.iterdir()}
    assert main(["report", "--only", "alpha", "--out", str(mine)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0] and f"--out {mine}" in err[0]
    assert {p.name: p.read_bytes() for p in mine.iterdir()} == before
    assert "fake_alpha.report" not in sys.modules or runs("alpha") == []


def test_a_report_elsewhere_says_so_in_its_hints(fake, tmp_path):
    """A report made with --out names that folder in its header and in every hint."""
    out = tmp_path / "elsewhere"
    assert main(["report", "--only", "alpha", "--out", str(out)]) == 0
    text = (out / "REPORT.md").read_text()
    assert f"Assembled by `soilwater report --only alpha --out {out}`" in text
    assert f"`soilwater report --only beta --out {out}`" in text   # beta never run
    assert (out / ".soilwater-report").is_file()
