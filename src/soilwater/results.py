"""Result files: written whole or not at all.

A failed run must leave no half-written output and never write NaN, so every writer
goes through a temporary file in the target folder and an atomic rename.

Which targets may be written, and how a single file is, is
:mod:`soilwater.targets`'s: a result folder holds its marker file, which lists its files,
and replaces only a folder that holds that marker and nothing else, claimed by one
process at a time.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from soilwater import fields
from soilwater.errors import SoilwaterError
from soilwater.locks import claim
from soilwater.targets import MARKER, check_output_folder, naming, publish, write_csv

#: Units of the history columns (:attr:`Result.units`), in the built-in cases' kPa, m, s
#: (a case in other units keeps its stress, length and time units); ``-`` is
#: dimensionless. Columns per probe or segment are named ``KIND@NAME``, with the unit of
#: ``KIND@``.
HISTORY_UNITS = {
    "time": "s", "dt": "s", "eps_a": "-", "p": "kPa", "q": "kPa", "err": "-", "gamma": "-",
    "settlement": "m", "iterations": "-", "substeps": "-", "residual": "-",
    "linear_iterations": "-", "uniqueness": "-", "min_angle": "degree",
    "min_quality": "-", "min_rcond": "-", "displacement": "-", "stress": "-",
    "energy": "-", "rebuilds": "-", "p_w@": "kPa", "ux@": "m", "uy@": "m", "settlement@": "m",
    "pressure@": "kPa",
}

#: Units of a snapshot's in-memory fields (:attr:`Snapshot.point_data`), as
#: :data:`HISTORY_UNITS`: displacement ``u`` (N, 2), pore pressure ``p_w`` in excess of
#: hydrostatic and ``p_eff``, q (compression positive), ``pc``, effective Cauchy
#: ``stress`` (N, 4: xx, yy, zz, xy), tension positive, ``stretching`` (N, 4), FEM's
#: ``velocity`` (N, 2), specific volume ``v``, MLS ``support_radius`` and
#: ``permeability`` k(e). The files hold more (:data:`soilwater.fields.UNITS`).
FIELD_UNITS = {"u": "m", "p_w": "kPa", "p_eff": "kPa", "q": "kPa", "pc": "kPa",
               "stress": "kPa", "stretching": "1/s", "velocity": "m/s", "v": "-",
               "support_radius": "m", "permeability": "m/s"}


def unit(column):
    """The unit of a history column (:data:`HISTORY_UNITS`); ``""`` if it has none listed.

    Examples
    --------
    >>> unit("p_w@centre"), unit("settlement"), unit("eps_a")
    ('kPa', 'm', '-')
    """
    kind, at, _ = column.partition("@")
    return HISTORY_UNITS.get(kind + at, "")


@dataclass
class Snapshot:
    """Fields at one output time: points (N, 2) [m] and named point arrays
    (:data:`FIELD_UNITS`); ``cells`` as meshio's ``[(type, (C, V) indices)]``, empty for a
    point cloud; ``quadratic``, for the quadratic FEM pairs, what their own nodes need
    (:func:`soilwater.fields.quadratic`)."""

    time: float
    points: np.ndarray
    point_data: dict
    cells: list = field(default_factory=list)
    quadratic: dict = None

    def mesh(self, case):
        """The snapshot as the :class:`meshio.Mesh` the VTU files hold
        (:func:`soilwater.fields.mesh`: cells for every method, u with three components,
        derived fields of ``case``)."""
        return fields.mesh(self, case)


@dataclass
class Result:
    """What every solver returns and ``soilwater run`` writes.

    Parameters
    ----------
    case : Case
        The case solved, resolved (defaults filled in; ``case.to_dict()`` is what
        ``summary.json`` holds).
    method : str
        ``efg``, ``fem-th``, ... (:data:`soilwater.methods.METHODS`).
    options : dict
        Method options as run (weights, scale factors, cells, penalty factor, ...).
    history : pandas.DataFrame
        One row per time step; at least ``time, eps_a, p, q, err`` for the coupled
        solvers. Units per column in :attr:`units`.
    snapshots : list of Snapshot
        Fields at output steps (meshless nodes as a point cloud, or a mesh with cells);
        :meth:`mesh` gives one as a :class:`meshio.Mesh`.
    summary : dict
        Timings, step count, convergence, metrics; JSON-serialisable.

    Examples
    --------
    >>> import soilwater
    >>> result = soilwater.solve(soilwater.load_case("terzaghi", "time.steps=1"),
    ...                          progress=False)
    >>> result.units["time"], result.units["p_w@p0"]
    ('s', 'kPa')
    >>> result.mesh().point_data["p_w"].shape == (len(result.case.nodes()),)
    True
    """

    case: object
    method: str
    options: dict
    history: pd.DataFrame
    snapshots: list
    summary: dict

    @property
    def units(self):
        """``{column: unit}`` of the :attr:`history` columns (:data:`HISTORY_UNITS`), in
        column order."""
        return {column: unit(column) for column in self.history.columns}

    def mesh(self, i=-1):
        """Snapshot ``i`` (the last by default) as a :class:`meshio.Mesh`, as written to
        ``fields_NNNN.vtu``: points (N, 3) [m], current configuration, z = 0; point and
        cell data in :data:`soilwater.fields.UNITS`; its time [s] in
        ``field_data["TimeValue"]`` (``result.snapshots[i].time``)."""
        return self.snapshots[i].mesh(self.case)

    def write(self, folder, what="folder"):
        """Write ``summary.json`` (the resolved case, every material parameter written
        out, the options, the versions of soilwater and its libraries, ``history_units``,
        the unit of each ``history.csv`` column, and ``field_units``, of each VTU
        field), ``history.csv``, ``fields.pvd``, VTU files and :data:`MARKER`, which
        lists them, to ``folder``.

        ``folder`` must pass :func:`soilwater.targets.check_output_folder`, when the
        call begins and again before it is replaced, and is held by
        :func:`soilwater.locks.claim` meanwhile. Everything goes to a hidden temporary
        sibling folder; only when it is complete does it take the place of ``folder`` (a
        previous result is renamed aside, the new one renamed in, the old one removed).
        On any failure, including KeyboardInterrupt, the temporary folder is removed and
        ``folder`` is left as it was; an error of the file system names the path in
        ``folder``, not in the temporary one.

        Parameters
        ----------
        folder : str or Path
        what : str
            How ``folder`` is named in a refusal (``"--out"`` from the command).

        Returns
        -------
        Path
            The resolved folder written.

        Raises
        ------
        InputError
            If ``folder`` is refused (:func:`soilwater.locks.claim`).
        SoilwaterError
            If a field holds NaN or infinity.
        """
        with claim(folder, what) as folder:
            try:
                tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.",
                                            suffix=".tmp"))
            except OSError as err:
                err.filename = str(folder)
                raise
            old = tmp.with_suffix(".old")
            try:
                with _in_place_of(tmp, folder):
                    publish(tmp, folder=True)
                    self._write_files(tmp)
                check_output_folder(folder, what)  # again: it may have changed meanwhile
                _swap(tmp, folder, old)
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)
                raise
            shutil.rmtree(old, ignore_errors=True)
        return folder

    def _write_files(self, folder):
        write_csv(self.history, folder / "history.csv")
        summary = {"case": self.case.to_dict(), "method": self.method,
                   "options": self.options, "versions": versions(),
                   "provenance": provenance(self.case),
                   "history_units": self.units, "field_units": fields.UNITS,
                   **self.summary}
        with naming(folder / "summary.json"):
            (folder / "summary.json").write_text(json.dumps(summary, indent=2,
                                                            default=float))
        self._write_fields(folder)
        marker = {"written_by": "soilwater", "version": version("soilwater"),
                  "note": "soilwater run replaces this folder whole, and only while it "
                          "holds nothing but these files",
                  "files": sorted(p.name for p in folder.iterdir())}
        with naming(folder / MARKER):
            (folder / MARKER).write_text(json.dumps(marker) + "\n")

    def _write_fields(self, folder):
        entries = []
        for k, snap in enumerate(self.snapshots):
            for name, values in snap.point_data.items():
                if not np.isfinite(values).all():
                    raise SoilwaterError(f"refusing to write field {name!r} at t = "
                                         f"{snap.time}: it holds NaN or infinity")
            name = f"fields_{k:04d}.vtu"
            with naming(folder / name):
                meshio.write(folder / name, snap.mesh(self.case))
            entries.append(f'    <DataSet timestep="{float(snap.time)!r}" file="{name}"/>')
        with naming(folder / "fields.pvd"):
            (folder / "fields.pvd").write_text(
                '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                "  <Collection>\n" + "\n".join(entries)
                + "\n  </Collection>\n</VTKFile>\n")


@contextmanager
def _in_place_of(tmp, folder):
    """Inside the block, an :class:`OSError` naming a path in the temporary folder
    ``tmp`` names that path in ``folder`` instead: where the user will look."""
    try:
        yield
    except OSError as err:
        name = Path(str(err.filename or ""))
        if name == tmp or tmp in name.parents:
            err.filename = str(folder / name.relative_to(tmp))
        raise


def _swap(new, folder, old):
    """Put folder ``new`` in the place of ``folder``; a previous ``folder`` goes to ``old``.

    If renaming ``new`` in fails, the previous ``folder`` is renamed back.
    """
    if folder.exists():
        os.rename(folder, old)
    try:
        os.rename(new, folder)
    except BaseException:
        if old.exists():
            os.rename(old, folder)
        raise


def versions():
    """Versions of soilwater and the libraries a result depends on (gmsh's only where it
    is installed)."""
    import scipy
    import skfem

    out = {"soilwater": version("soilwater"), "numpy": np.__version__,
           "scipy": scipy.__version__, "scikit-fem": skfem.__version__,
           "meshio": meshio.__version__}
    try:
        out["gmsh"] = version("gmsh")
    except PackageNotFoundError:
        pass
    return out


def provenance(case):
    """How a result was made, for ``summary.json``: ``date`` (UTC), ``command`` (this
    process's command line), ``source`` (the git commit of soilwater's checkout, with
    ``-dirty`` for uncommitted changes; None for an installed copy) and, for a case on a
    user's mesh, ``mesh``: its path, content hash (sha256), vertex and triangle counts
    and its region names, the index of the VTU cell field ``region``."""
    out = {"date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "command": " ".join(sys.argv), "source": _commit()}
    mesh = case.geometry.mesh
    if mesh is not None:
        out["mesh"] = {"path": str(mesh.path), "sha256": mesh.digest,
                       "vertices": len(mesh.points), "triangles": len(mesh.triangles),
                       "regions": list(mesh.regions)}
    return out


def _commit():
    """The git commit of the checkout soilwater runs from (``-dirty`` when its sources
    differ), or None outside a git checkout."""
    folder = Path(__file__).parent
    try:
        head = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"],
                              capture_output=True, text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", str(folder), "status", "--porcelain", "."],
                               capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    if head.returncode:
        return None
    return head.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
