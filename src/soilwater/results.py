"""Result files: written whole or not at all.

A failed run must leave no half-written output and never write NaN, so every writer
goes through a temporary file in the target folder and an atomic rename.

Which targets may be written, and how a single file is, is
:mod:`soilwater.targets`'s: a result folder holds its marker file and replaces only a
folder that does.
"""

import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from importlib.metadata import version
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from soilwater import fields
from soilwater.errors import SoilwaterError
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
        cell data in :data:`soilwater.fields.UNITS`. Its time [s] is
        ``result.snapshots[i].time``."""
        return self.snapshots[i].mesh(self.case)

    def write(self, folder):
        """Write ``summary.json`` (the resolved case, every material parameter written
        out, the options, the versions of soilwater and its libraries, ``history_units``,
        the unit of each ``history.csv`` column, and ``field_units``, of each VTU
        field), ``history.csv``, ``fields.pvd``, VTU files and :data:`MARKER` to
        ``folder``.

        ``folder`` must pass :func:`soilwater.targets.check_output_folder`. Everything goes to a hidden
        temporary sibling folder; only when it is complete does it take the place of
        ``folder`` (a previous result is renamed aside, the new one renamed in, the old one
        removed). On any failure, including KeyboardInterrupt, the temporary folder is
        removed and ``folder`` is left as it was.

        Returns
        -------
        Path
            The resolved folder written.
        """
        folder = check_output_folder(folder)
        with naming(folder):
            folder.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.",
                                        suffix=".tmp"))
        old = tmp.with_suffix(".old")
        try:
            publish(tmp, folder=True)
            self._write_files(tmp)
            check_output_folder(folder)  # again: the folder may have changed during the run
            _swap(tmp, folder, old)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        shutil.rmtree(old, ignore_errors=True)
        return folder

    def _write_files(self, folder):
        marker = {"written_by": "soilwater", "version": version("soilwater"),
                  "note": "soilwater run replaces this folder whole"}
        with naming(folder / MARKER):
            (folder / MARKER).write_text(json.dumps(marker) + "\n")
        write_csv(self.history, folder / "history.csv")
        summary = {"case": self.case.to_dict(), "method": self.method,
                   "options": self.options, "versions": versions(),
                   "history_units": self.units, "field_units": fields.UNITS,
                   **self.summary}
        with naming(folder / "summary.json"):
            (folder / "summary.json").write_text(json.dumps(summary, indent=2,
                                                            default=float))
        self._write_fields(folder)

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
    """Versions of soilwater and the libraries a result depends on."""
    import scipy
    import skfem

    return {"soilwater": version("soilwater"), "numpy": np.__version__,
            "scipy": scipy.__version__, "scikit-fem": skfem.__version__,
            "meshio": meshio.__version__}
