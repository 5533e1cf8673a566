"""One process per result folder: :func:`claim` locks a folder while a run writes it, so
that a second run on the same ``--out`` is refused at once instead of replacing the
first one's result."""

import fcntl
import os
from contextlib import contextmanager

from soilwater.errors import InputError
from soilwater.targets import check_output_folder, remove_empty, shown_path

#: Result folders locked by this process (:func:`claim`).
_CLAIMED = set()


@contextmanager
def claim(path, what="folder"):
    """Hold the result folder ``path`` for this process while the block runs: checked
    (:func:`check_output_folder`), then locked, so that a second process claiming it
    meanwhile is refused at once.

    The lock is the file ``.NAME.lock`` beside the folder, holding this process's id,
    under an exclusive :func:`fcntl.flock`. It is removed when the block ends, by an
    exception too; the system releases the lock of a process that dies, and a lock file
    left behind is then taken over. Folders made to hold the lock are removed again if
    nothing was written into them. A claim of a folder this process already holds
    (:meth:`Result.write` inside the command's claim) is checked and yields at once.

    Parameters
    ----------
    path : str or Path
    what : str
        How the caller's argument is named in a refusal (``"--out"`` from the command).

    Yields
    ------
    Path
        The resolved folder.

    Raises
    ------
    InputError
        If :func:`check_output_folder` refuses the folder, another process holds it, or
        the folder's lock cannot be created there (naming ``path``).
    """
    folder = check_output_folder(path, what)
    if folder in _CLAIMED:
        yield folder
        return
    made = [p for p in (folder.parent, *folder.parent.parents) if not p.exists()]
    lock = folder.parent / f".{folder.name}.lock"
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        fd = _lock(lock)
    except OSError as err:
        remove_empty(made)
        reason = err.strerror or err
        raise InputError(f"{what} {shown_path(path, folder)}: cannot be created ({reason}); "
                         "name a folder you can write in") from None
    if fd is None:
        remove_empty(made)
        raise InputError(f"{what} {shown_path(path, folder)} is being written by another "
                         f"soilwater run ({_holder(lock)}); wait for it to end, or choose "
                         f"another {what}")
    _CLAIMED.add(folder)
    try:
        yield folder
    finally:
        _CLAIMED.discard(folder)
        if _same_file(fd, lock):  # unlinked before the lock is released: see _lock
            lock.unlink()
        os.close(fd)
        remove_empty(made)


def _lock(path):
    """Open, lock and fill the lock file ``path``; its descriptor, or None if another
    process holds it. A file its holder unlinked between our open and our lock is no
    lock any more: the path is opened again."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        held = False
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            held = _same_file(fd, path)
            if held:
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode())
                return fd
        except BlockingIOError:
            os.close(fd)
            return None
        except BaseException:
            if held:
                path.unlink(missing_ok=True)
            os.close(fd)
            raise
        os.close(fd)


def _same_file(fd, path):
    """Whether ``path`` still names the file open as ``fd``."""
    try:
        return os.path.samestat(os.fstat(fd), os.stat(path))
    except FileNotFoundError:
        return False


def _holder(lock):
    """Where the lock is, and its holder's process id once written."""
    try:
        pid = lock.read_text().strip()
    except OSError:
        pid = ""
    return f"process {pid}, lock {lock}" if pid.isdigit() else f"lock {lock}"
