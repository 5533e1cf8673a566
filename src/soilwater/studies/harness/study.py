"""One shape for every study of the report, and the store of their last outputs.

A study is a module (``soilwater.studies.<folder>.report``) with

* ``NAME``: its name on the command line (``soilwater report --only NAME``);
* ``NEEDS``: names of the studies whose saved data it reads (usually empty);
* ``run(root, inputs) -> dict``: runs the study, writes its tables under
  ``root/tables`` and figures under ``root/figures`` and returns the numbers its section
  needs (``inputs`` maps each name of ``NEEDS`` to that study's saved data);
* ``section(data) -> list of str``: its REPORT.md lines from those numbers.

:func:`save` keeps what ``run`` returned under ``root/studies/NAME.pkl`` beside
``NAME.json``: the hash of the sources it was made from (:func:`source_hash`), the
settings, the wall time and the solver runs it made and read from the cache.
:func:`load` reads them back, so REPORT.md can be rebuilt from every study's last
outputs while only some studies are rerun, and a section whose sources changed since is
marked stale.
"""

import hashlib
import json
import os
import pickle
import time
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path

from soilwater.studies.harness import runner
from soilwater.studies.harness.paths import PACKAGE

#: Package folders that are not the shared library: the solvers, each a study's input
#: only if it runs or imports them, and the studies.
_SOLVERS = ("efg", "fem")
_APART = (*_SOLVERS, "studies")


@dataclass(frozen=True)
class Study:
    """A study of the report: its name, the module implementing it and the studies whose
    saved data it reads."""

    name: str
    module: str

    def load(self):
        """The study's module (imported on first use)."""
        return import_module(self.module)

    @property
    def needs(self):
        return tuple(getattr(self.load(), "NEEDS", ()))

    @property
    def folder(self):
        """The study's source folder."""
        return Path(self.load().__file__).parent


@dataclass
class Saved:
    """A study's last output: ``data`` (what its ``run`` returned) and ``meta`` (``code``:
    the source hash; ``settings``; ``seconds``; ``runs`` and ``cached`` solver runs;
    ``made``: UTC time)."""

    data: dict
    meta: dict


def source_hash(folders, solvers=_SOLVERS):
    """Hash of the shared library sources (every ``.py``, ``.toml`` and built-in mesh of
    the package outside ``efg/``, ``fem/`` and ``studies/``), the ``solvers`` folders, the
    study harness and ``folders``: 16 hex digits.

    A change to the material, the built-in cases, the harness, one of ``solvers`` or a
    study's own folder changes it; a change to another solver or to another study's folder
    does not.
    """
    digest = hashlib.sha256()
    library = [(PACKAGE, p) for p in sorted(PACKAGE.rglob("*"))
               if p.suffix in (".py", ".toml", ".msh", ".geo")
               and (p.relative_to(PACKAGE).parts[0] not in _APART
                    or p.relative_to(PACKAGE).parts[0] in solvers)]
    own = [(Path(folder), p) for folder in (PACKAGE / "studies" / "harness", *folders)
           for p in sorted(Path(folder).rglob("*.py"))]
    for top, path in library + own:
        digest.update(path.relative_to(top).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def inputs_hash(study, registry, solvers=_SOLVERS):
    """The source hash of ``study``: the shared library, the ``solvers`` folders it used,
    its own folder and the folders of the studies it needs (``registry``: name ->
    :class:`Study`)."""
    folders = [study.folder] + [registry[n].folder for n in study.needs]
    return source_hash(folders, solvers)


def imported_solvers(study, registry):
    """The solver folders (``efg``, ``fem``) that ``study``'s own sources, or those of the
    studies it needs, import directly (not through the runner)."""
    folders = [study.folder] + [registry[n].folder for n in study.needs]
    text = "".join(p.read_text() for folder in folders for p in Path(folder).rglob("*.py"))
    return {name for name in _SOLVERS if f"soilwater.{name}" in text}


def solvers(saved):
    """The solver folders a saved output depends on (both when it does not say)."""
    return tuple(saved.meta.get("solvers", _SOLVERS))


def paths(root, name):
    """Where a study's output is saved: ``root/studies/NAME.pkl`` and ``NAME.json``."""
    folder = Path(root) / "studies"
    return folder / f"{name}.pkl", folder / f"{name}.json"


def save(root, name, data, meta):
    """Store a study's output under ``root/studies``: ``NAME.pkl`` (the data) and
    ``NAME.json`` (the meta). Returns the two paths."""
    pkl, js = paths(root, name)
    pkl.parent.mkdir(parents=True, exist_ok=True)
    tmp = pkl.with_suffix(f".{os.getpid()}.tmp")
    with tmp.open("wb") as fh:
        pickle.dump(data, fh)
    os.replace(tmp, pkl)
    js.write_text(json.dumps(meta, indent=2, sort_keys=True) + "\n")
    return pkl, js


def load(root, name):
    """A study's saved output, or None if it has not been run (or cannot be read)."""
    pkl, js = paths(root, name)
    try:
        meta = json.loads(js.read_text())
        with pkl.open("rb") as fh:
            return Saved(pickle.load(fh), meta)
    except (OSError, ValueError, EOFError, AttributeError, ImportError,
            pickle.UnpicklingError):
        return None


def run(study, root, inputs, registry, settings):
    """Run ``study`` into ``root``, save its data and return the :class:`Saved`.

    Its meta records the solver folders it used (those of the runner's jobs and those its
    sources import) and the source hash over them (:func:`inputs_hash`); its runs and
    cached runs are its share of the runner's tally.
    """
    counts, before = runner.COUNTS, dict(runner.COUNTS)
    runner.USED.clear()
    tic = time.perf_counter()
    data = study.load().run(Path(root), inputs)
    used = sorted(runner.USED | imported_solvers(study, registry))
    meta = {"code": inputs_hash(study, registry, used), "solvers": used,
            "settings": settings,
            "seconds": round(time.perf_counter() - tic, 1),
            "runs": counts["runs"] - before["runs"],
            "cached": counts["cached"] - before["cached"],
            "made": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    save(root, study.name, data, meta)
    return Saved(data, meta)
