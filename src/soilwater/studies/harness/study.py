"""One shape for every study of the report, and the store of their last outputs.

A study is a module (``soilwater.studies.<folder>.report``) with

* ``NAME``: its name on the command line (``soilwater report --only NAME``);
* ``NEEDS``: names of the studies whose saved data it reads (usually empty);
* ``run(root, inputs) -> dict``: runs the study, writes its tables under
  ``root/tables`` and figures under ``root/figures`` and returns the numbers its section
  needs (``inputs`` maps each name of ``NEEDS`` to that study's saved data);
* ``section(data) -> list of str``: its REPORT.md lines from those numbers.

:func:`save` keeps what ``run`` returned under ``root/studies/NAME.pkl`` beside
``NAME.json``: the code hash of every module it could execute and their digest
(:func:`dependencies`), the settings, the wall time and the solver runs it made and read
from the cache. :func:`load` reads them back, so REPORT.md can be rebuilt from every
study's last outputs while only some studies are rerun, and a section whose code changed
since (:func:`changed`; not its comments or docstrings) is marked stale.
"""

import json
import os
import pickle
import time
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path

from soilwater.studies.harness import runner, sources

#: The solver folders: each a study's input only if it runs or imports them.
_SOLVERS = sources.SOLVERS


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


def dependencies(study, registry, solvers=_SOLVERS):
    """``{path: code hash}`` of what ``study`` is made of: the modules its own module,
    those of the studies it needs and the ``solvers`` it used can import, and the
    library's data files (:func:`soilwater.studies.harness.sources.dependencies`)."""
    roots = [study.module, *(registry[n].module for n in study.needs),
             *(f"soilwater.{s}.{m}" for s in solvers for m in ("solver", "statics"))]
    return sources.dependencies(roots, solvers)


def changed(saved):
    """The sources of a saved output that changed since it was made (paths relative to
    the package, sorted); all of them (``["(not recorded)"]``) for output that did not
    record its sources."""
    modules = saved.meta.get("modules")
    return ["(not recorded)"] if modules is None else sources.changed(modules)


def imported_solvers(study, registry):
    """The solver folders (``efg``, ``fem``) that ``study``'s own sources, or those of the
    studies it needs, import directly (not through the runner)."""
    folders = [study.folder] + [registry[n].folder for n in study.needs]
    text = "".join(p.read_text() for folder in folders for p in Path(folder).rglob("*.py"))
    return {name for name in _SOLVERS if f"soilwater.{name}" in text}


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
    sources import), the code hash of every module it could execute (:func:`dependencies`)
    and their digest; its runs and cached runs are its share of the runner's tally.
    """
    counts, before = runner.COUNTS, dict(runner.COUNTS)
    runner.USED.clear()
    tic = time.perf_counter()
    data = study.load().run(Path(root), inputs)
    used = sorted(runner.USED | imported_solvers(study, registry))
    modules = dependencies(study, registry, used)
    meta = {"code": sources.digest(modules), "modules": modules, "solvers": used,
            "settings": settings,
            "seconds": round(time.perf_counter() - tic, 1),
            "runs": counts["runs"] - before["runs"],
            "cached": counts["cached"] - before["cached"],
            "made": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    save(root, study.name, data, meta)
    return Saved(data, meta)
