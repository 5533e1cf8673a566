"""Result files: written whole or not at all.

A failed run must leave no half-written output and never write NaN, so every writer
goes through a temporary file in the target folder and an atomic rename.
"""

import json
import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from soil.errors import SoilwaterError


def write_csv(frame, path):
    """Write a DataFrame to ``path`` atomically, refusing non-finite numbers.

    Parameters
    ----------
    frame : pandas.DataFrame
    path : str or Path

    Raises
    ------
    SoilwaterError
        If a numeric column holds NaN or infinity (nothing is written).
    """
    numbers = frame.select_dtypes("number").to_numpy(dtype=float)
    if not np.isfinite(numbers).all():
        raise SoilwaterError(f"refusing to write {path}: the table holds NaN or infinity")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", newline="") as fh:
            frame.to_csv(fh, index=False)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


@dataclass
class Snapshot:
    """Fields at one output time: points (N, 2) [m] and named point arrays."""

    time: float
    points: np.ndarray
    point_data: dict
    cells: list = field(default_factory=list)


@dataclass
class Result:
    """What every solver returns and ``soilwater run`` writes (design.md section 6).

    Parameters
    ----------
    case : Case
    method : str
        ``efg``, ``fem-th``, ...
    options : dict
        Method options as run (weights, scale factors, cells, penalty factor, ...).
    history : pandas.DataFrame
        One row per step; at least ``time, eps_a, p, q, err`` for the coupled solvers.
    snapshots : list of Snapshot
        Fields at output steps (meshless nodes as a point cloud, or a mesh with cells).
    summary : dict
        Timings, step count, convergence, metrics; JSON-serialisable.
    """

    case: object
    method: str
    options: dict
    history: pd.DataFrame
    snapshots: list
    summary: dict

    def write(self, folder):
        """Write ``summary.json``, ``history.csv``, ``fields.pvd`` and VTU files.

        Everything goes to a temporary sibling folder that replaces ``folder`` only when
        complete, so a failure leaves ``folder`` as it was.
        """
        folder = Path(folder)
        folder.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}."))
        try:
            write_csv(self.history, tmp / "history.csv")
            summary = {"case": self.case.to_dict(), "method": self.method,
                       "options": self.options, "versions": versions(), **self.summary}
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
            self._write_fields(tmp)
            if folder.exists():
                shutil.rmtree(folder)
            os.replace(tmp, folder)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return folder

    def _write_fields(self, folder):
        entries = []
        for k, snap in enumerate(self.snapshots):
            for name, values in snap.point_data.items():
                if not np.isfinite(values).all():
                    raise SoilwaterError(f"refusing to write field {name!r} at t = "
                                         f"{snap.time}: it holds NaN or infinity")
            cells = snap.cells or [("vertex", np.arange(len(snap.points))[:, None])]
            name = f"fields_{k:04d}.vtu"
            points3 = np.column_stack([snap.points, np.zeros(len(snap.points))])
            meshio.write(folder / name, meshio.Mesh(points3, cells, point_data=snap.point_data))
            entries.append(f'    <DataSet timestep="{snap.time!r}" file="{name}"/>')
        (folder / "fields.pvd").write_text(
            '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
            "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")


def versions():
    """Versions of soilwater and the libraries a result depends on."""
    from importlib.metadata import version

    import scipy
    import skfem

    return {"soilwater": version("soilwater"), "numpy": np.__version__,
            "scipy": scipy.__version__, "scikit-fem": skfem.__version__,
            "meshio": meshio.__version__}
