"""Result files: written whole or not at all.

A failed run must leave no half-written output and never write NaN, so every writer
goes through a temporary file in the target folder and an atomic rename.

Nothing deletes a file or folder that soilwater did not write: a result folder holds the
marker file :data:`MARKER`, and :func:`check_output_folder` refuses any other target; a
single output file (``soilwater path``, ``soilwater infsup``) replaces only a file that
soilwater wrote (:func:`check_output_file`), never through a symbolic link. Every target
is checked before any work, an error of the file system names its path, and what is
written takes the user's umask.
"""

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib.metadata import version
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from soilwater import fields
from soilwater.errors import InputError, SoilwaterError

#: File in every result folder :meth:`Result.write` writes; only a folder holding it (or an
#: empty one) is ever replaced.
MARKER = ".soilwater-output"

_FIX = "name a new or empty folder, e.g. --out runs/NAME"
#: The ``Software`` text of every PNG file soilwater writes: how it knows its own figures.
SOFTWARE = "soilwater"


def umask():
    """The process's file-creation mask (read without changing it for longer than a
    call)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def publish(path, folder=False):
    """Give a file (or ``folder``) made by :mod:`tempfile`, which makes them private
    (0600, 0700), the permissions an ordinary ``open`` (``mkdir``) would: 0666 (0777)
    less the umask."""
    os.chmod(path, (0o777 if folder else 0o666) & ~umask())


@contextmanager
def naming(path):
    """Inside the block, an :class:`OSError` that names no file (a write failing on a
    full disk) is given ``path``, so its one-line message says where."""
    try:
        yield
    except OSError as err:
        if err.filename is None:
            err.filename = str(path)
        raise


def _writable_parent(path, shown):
    """Refuse ``path`` when its nearest existing ancestor is not a folder soilwater can
    write in (a parent that is a file, a read-only folder): found before any work."""
    parent = path.parent
    while not parent.exists():
        if parent.is_symlink():
            raise InputError(f"--out {shown}: {parent} is a broken symbolic link; name a "
                             "path through existing folders or new ones")
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"--out {shown}: {parent} is a file, not a folder; name a path "
                         "inside a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"--out {shown}: cannot write in {parent} (permission denied); "
                         "name a folder you can write in")


def check_output_folder(path):
    """Resolve a result folder, refusing one that soilwater must not write or replace.

    ``~`` is expanded and symbolic links, ``.`` and ``..`` are resolved first. A folder
    that does not exist yet, an empty folder and a folder holding :data:`MARKER` (a
    previous result) are accepted.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Path
        The resolved folder.

    Raises
    ------
    InputError
        If the folder is the current folder or holds it, is the home folder or holds it,
        is a file, or is a non-empty folder without :data:`MARKER`.

    Examples
    --------
    >>> check_output_folder(".")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: --out . (= ...): the current folder or a folder holding it ...
    """
    folder = Path(path).expanduser().resolve()
    shown = str(path) if str(path) == str(folder) else f"{path} (= {folder})"
    cwd, home = Path.cwd().resolve(), Path.home().resolve()
    if folder == cwd or folder in cwd.parents:
        raise InputError(f"--out {shown}: the current folder or a folder holding it "
                         f"cannot be a result folder, which is replaced whole; {_FIX}")
    if folder == home or folder in home.parents:
        raise InputError(f"--out {shown}: the home folder or a folder holding it cannot "
                         f"be a result folder, which is replaced whole; {_FIX}")
    if folder.exists() and not folder.is_dir():
        raise InputError(f"--out {shown} is a file, not a folder; {_FIX}")
    _writable_parent(folder, shown)
    if folder.is_dir() and not (folder / MARKER).is_file() and any(folder.iterdir()):
        raise InputError(f"--out {shown} holds files soilwater did not write (no {MARKER} "
                         f"file); {_FIX}, or empty it yourself")
    return folder


def written_by_soilwater(path, columns=None):
    """True if the existing file ``path`` is one soilwater wrote: a PNG whose
    ``Software`` text is :data:`SOFTWARE`, or a CSV whose header is ``columns``."""
    path = Path(path)
    if path.suffix.lower() == ".png":
        from PIL import Image

        try:
            with Image.open(path) as image:
                return image.info.get("Software", "").startswith(SOFTWARE)
        except OSError:
            return False
    with open(path, newline="", errors="replace") as fh:
        return columns is not None and fh.readline().rstrip("\r\n") == ",".join(columns)


def check_output_file(path, columns=None):
    """Resolve an output file, refusing one that soilwater must not write or replace.

    Accepted: a new file in a folder that exists or can be made, or a regular file that
    soilwater wrote (:func:`written_by_soilwater`: a CSV with the header ``columns``, a
    PNG of soilwater's), which is then replaced whole.

    Parameters
    ----------
    path : str or Path
    columns : sequence of str, optional
        The header of the CSV to be written.

    Returns
    -------
    Path
        ``path`` with ``~`` expanded; its folders' links are followed, its own name not.

    Raises
    ------
    InputError
        If ``path`` is a symbolic link, a folder or another non-regular file, a file
        soilwater did not write, or lies under a file or a folder that cannot be
        written.

    Examples
    --------
    >>> check_output_file("/dev/stdout")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: --out /dev/stdout is a symbolic link: ...
    """
    path = Path(path).expanduser()
    shown = str(path)
    if path.is_symlink():
        raise InputError(f"--out {shown} is a symbolic link: soilwater writes through "
                         "none; name the file itself")
    if path.is_dir():
        raise InputError(f"--out {shown} is a folder: name a file in it, e.g. "
                         f"{path / ('figure' if path.suffix == '.png' else 'path') }"
                         f"{path.suffix or '.csv'}")
    if path.exists() and not path.is_file():
        raise InputError(f"--out {shown} is not a regular file (a device, a pipe, a "
                         "socket); name a file")
    _writable_parent(path, shown)
    if path.exists() and not written_by_soilwater(path, columns):
        raise InputError(f"--out {shown} exists and soilwater did not write it; name a "
                         "new file, or move it away yourself")
    return path


def write_csv(frame, path):
    """Write a DataFrame to ``path`` atomically, refusing non-finite numbers.

    ``path`` must pass :func:`check_output_file` with the frame's columns: a file that
    already exists is replaced only if it is an earlier table of the same columns.

    Parameters
    ----------
    frame : pandas.DataFrame
    path : str or Path

    Raises
    ------
    InputError
        If ``path`` is refused by :func:`check_output_file` (nothing is written).
    SoilwaterError
        If a numeric column holds NaN or infinity (nothing is written).
    """
    path = check_output_file(path, list(frame.columns))
    numbers = frame.select_dtypes("number").to_numpy(dtype=float)
    if not np.isfinite(numbers).all():
        raise SoilwaterError(f"refusing to write {path}: the table holds NaN or infinity")
    with naming(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.",
                                   suffix=".tmp")
        try:
            with os.fdopen(fd, "w", newline="") as fh:
                frame.to_csv(fh, index=False)
            publish(tmp)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    return path


#: Units of the history columns (:attr:`Result.units`), in the built-in cases' kPa, m, s
#: (a case in other units keeps its stress, length and time units); ``-`` is
#: dimensionless. Columns per probe or segment are named ``KIND@NAME``, with the unit of
#: ``KIND@``.
HISTORY_UNITS = {
    "time": "s", "dt": "s", "eps_a": "-", "p": "kPa", "q": "kPa", "err": "-", "gamma": "-",
    "settlement": "m", "iterations": "-", "substeps": "-", "residual": "-",
    "linear_iterations": "-", "uniqueness": "-", "min_angle": "degree",
    "min_quality": "-", "min_rcond": "-", "displacement": "-", "stress": "-",
    "energy": "-", "rebuilds": "-", "p_w@": "kPa", "settlement@": "m", "pressure@": "kPa",
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

        ``folder`` must pass :func:`check_output_folder`. Everything goes to a hidden
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
