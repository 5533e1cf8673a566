"""Where soilwater may write: output targets checked before any work, written whole.

Nothing deletes a file or folder that soilwater did not write: a result folder holds the
marker file :data:`MARKER`, which lists the files written with it, and
:func:`check_output_folder` refuses any other target, and a previous result holding
anything else; :func:`soilwater.locks.claim` keeps a second process from writing the same
result folder. A report folder is checked likewise
(:mod:`soilwater.studies.harness.folder`). A single output file (``soilwater path``,
``soilwater infsup``) replaces only a file that soilwater wrote (:func:`check_output_file`), never
through a symbolic link. Every target is checked before any work, an error of the file
system names its path (:func:`naming`), and what is written takes the user's umask
(:func:`publish`).
"""

import json
import os
import re
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from soilwater.errors import InputError, SoilwaterError

#: File in every result folder :meth:`Result.write` writes; only a folder holding it (or an
#: empty one) is ever replaced, and only while it holds nothing but the files the marker
#: lists (its JSON's ``files``).
MARKER = ".soilwater-output"

#: The files of a result whose marker lists none (written before markers did).
RESULT_FILES = re.compile(r"summary\.json|history\.csv|fields\.pvd|fields_\d{4,}\.vtu")

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


def _writable_parent(path, shown, what="--out"):
    """Refuse ``path`` when its nearest existing ancestor is not a folder soilwater can
    write in (a parent that is a file, a read-only folder): found before any work."""
    parent = path.parent
    while not parent.exists():
        if parent.is_symlink():
            raise InputError(f"{what} {shown}: {parent} is a broken symbolic link; name a "
                             "path through existing folders or new ones")
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{what} {shown}: {parent} is a file, not a folder; name a path "
                         "inside a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"{what} {shown}: cannot write in {parent} (permission denied); "
                         "name a folder you can write in")


def shown_path(path, folder):
    """``path`` as the user gave it, and the resolved ``folder`` when they differ."""
    return str(path) if str(path) == str(folder) else f"{path} (= {folder})"


def _new_folder(what):
    """The fix for a refused folder: a new or empty one, with an example for an option."""
    return "name a new or empty folder" + (f", e.g. {what} runs/NAME"
                                          if what.startswith("--") else "")


def target_folder(path, what, kind, fix):
    """Resolve ``path`` (``~``, links, ``.`` and ``..``) as a ``kind`` folder to write,
    refusing the current or home folder or one holding them, a file, and a path under a
    file or a folder that cannot be written; returns the folder and how to show it."""
    folder = Path(path).expanduser().resolve()
    shown = shown_path(path, folder)
    for place, name in ((Path.cwd(), "current"), (Path.home(), "home")):
        place = place.resolve()
        if folder == place or folder in place.parents:
            raise InputError(f"{what} {shown}: the {name} folder or a folder holding it "
                             f"cannot be a {kind}; {fix}")
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{what} {shown} is a file, not a folder; {fix}")
    _writable_parent(folder, shown, what)
    return folder, shown


def listing(entries):
    """Up to three entry names (a folder's with ``/``), sorted, and ``...`` for more."""
    names = sorted(e.name + ("/" if e.is_dir() and not e.is_symlink() else "")
                   for e in entries)
    return ", ".join(names[:3] + (["..."] if len(names) > 3 else []))


def count_entries(count):
    """``"1 entry"``, ``"2 entries"``."""
    return f"{count} {'entry' if count == 1 else 'entries'}"


def _foreign(folder):
    """The entries of the result ``folder`` that are not its files: those its
    :data:`MARKER` lists, or, for a marker that lists none, :data:`RESULT_FILES`."""
    try:
        files = json.loads((folder / MARKER).read_text()).get("files")
    except (ValueError, AttributeError):
        files = None

    def ours(name):
        if isinstance(files, list):
            return name == MARKER or name in files
        return name == MARKER or bool(RESULT_FILES.fullmatch(name))

    return [e for e in folder.iterdir()
            if not (ours(e.name) and e.is_file() and not e.is_symlink())]


def check_output_folder(path, what="folder"):
    """Resolve a result folder, refusing one that soilwater must not write or replace.

    ``~`` is expanded and symbolic links, ``.`` and ``..`` are resolved first. A folder
    that does not exist yet, an empty folder and a previous result (a folder holding
    :data:`MARKER` and only the files that marker lists) are accepted.

    Parameters
    ----------
    path : str or Path
    what : str
        How the caller's argument is named in a refusal (``"--out"`` from the command).

    Returns
    -------
    Path
        The resolved folder.

    Raises
    ------
    InputError
        If the folder is the current folder or holds it, is the home folder or holds it,
        is a file, is a non-empty folder without :data:`MARKER`, or is a previous result
        that also holds files or folders soilwater did not write (up to three are named,
        and their count), which replacing it would delete.

    Examples
    --------
    >>> check_output_folder(".", "--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: --out . (= ...): the current folder or a folder holding it ...
    """
    fix = _new_folder(what)
    folder, shown = target_folder(path, what, "result folder, which is replaced whole",
                                   fix)
    if not folder.is_dir() or not any(folder.iterdir()):
        return folder
    if not (folder / MARKER).is_file():
        raise InputError(f"{what} {shown} holds files soilwater did not write (no {MARKER} "
                         f"file); {fix}, or empty it yourself")
    foreign = _foreign(folder)
    if foreign:
        raise InputError(f"{what} {shown} is a previous result holding "
                         f"{count_entries(len(foreign))} soilwater did not write "
                         f"({listing(foreign)}), which replacing it would delete; move "
                         f"them out of it, or choose another {what}")
    return folder


def remove_empty(folders):
    """Remove each of ``folders`` (deepest first) that is empty."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            pass


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
