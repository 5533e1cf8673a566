"""The documentation builds with warnings as errors (the gallery not run)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_the_docs_build_without_warnings(tmp_path):
    pytest.importorskip("sphinx", reason="sphinx is not installed: pip install -e '.[docs]'")
    pytest.importorskip("sphinx_gallery", reason="sphinx-gallery is not installed: "
                        "pip install -e '.[docs]'")
    # A copy of the sources: the build writes the gallery and the API stubs beside them.
    source = tmp_path / "docs"
    shutil.copytree(DOCS, source, ignore=shutil.ignore_patterns(
        "_build", "auto_examples", "generated", "__pycache__"))
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-D", "plot_gallery=0", str(source), str(tmp_path / "html")],
        timeout=300, check=False, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-5000:]
    html = tmp_path / "html"
    for page in ("index", "case_reference", "api", "auto_examples/index",
                 "api/generated/soilwater.case.schema"):
        assert (html / f"{page}.html").is_file(), page
    reference = (html / "case_reference.html").read_text()
    assert all(key in reference for key in ("permeability_law", "stabilisation_factor",
                                            "remesh_quality", "on_failure"))
    assert not list((html / "api" / "generated").glob("soilwater.studies*"))
