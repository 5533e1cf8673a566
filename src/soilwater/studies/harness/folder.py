"""The report's folder: ``soilwater report`` writes only into a new or empty folder or a
report it wrote, which it marks with :data:`REPORT_MARKER` before writing anything there
(:mod:`soilwater.targets` holds the rules every output target shares)."""

import json
from importlib.metadata import version
from pathlib import Path

from soilwater.errors import InputError
from soilwater.targets import MARKER, count_entries, listing, naming, target_folder

#: File in every report folder soilwater writes (:func:`mark_report_folder`).
REPORT_MARKER = ".soilwater-report"

#: The first line of every REPORT.md soilwater writes (quick or full).
REPORT_HEADING = "# soilwater report"


def check_report_folder(path, what="folder"):
    """Resolve a report folder, refusing one that ``soilwater report`` must not write in.

    ``~`` is expanded and symbolic links, ``.`` and ``..`` are resolved first. Accepted:
    a folder that does not exist yet, an empty folder, and a report of soilwater's: a
    folder holding :data:`REPORT_MARKER`, or, written before that marker, a ``REPORT.md``
    whose first line is :data:`REPORT_HEADING` beside a ``studies`` folder.

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
        If the folder is the current folder (the project's own files) or holds it, is the
        home folder or holds it, is a file, is a result of ``soilwater run``, holds a
        ``REPORT.md`` soilwater did not write, or holds other files and is no report.

    Examples
    --------
    >>> check_report_folder(".", "--out")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: --out . (= ...): the current folder or a folder holding it ...
    """
    fix = "name a new or empty folder, or a report soilwater wrote"
    folder, shown = target_folder(path, what, "report folder", fix)
    if not folder.is_dir() or (folder / REPORT_MARKER).is_file():
        return folder
    if (folder / MARKER).is_file():
        raise InputError(f"{what} {shown} is a result of soilwater run (it holds "
                         f"{MARKER}), not a report folder; {fix}")
    report = folder / "REPORT.md"
    if report.is_file():
        with open(report, errors="replace") as fh:
            heading = fh.readline()
        if heading.startswith(REPORT_HEADING) and (folder / "studies").is_dir():
            return folder
        raise InputError(f"{what} {shown}: {report} was not written by soilwater report; "
                         f"move it out of the folder, or {fix}")
    entries = list(folder.iterdir())
    if entries:
        raise InputError(f"{what} {shown} is not a soilwater report (no {REPORT_MARKER}) "
                         f"and holds {count_entries(len(entries))} ({listing(entries)}); {fix}")
    return folder


def mark_report_folder(folder):
    """Make ``folder`` (and its parents) if needed and mark it as a report of
    soilwater's with :data:`REPORT_MARKER`, before the report writes anything there, so
    that a report stopped half-way is still recognised by :func:`check_report_folder`.

    Returns
    -------
    Path
        ``folder``.
    """
    folder = Path(folder)
    marker = folder / REPORT_MARKER
    with naming(marker):
        folder.mkdir(parents=True, exist_ok=True)
        if not marker.is_file():
            marker.write_text(json.dumps({
                "written_by": "soilwater", "version": version("soilwater"),
                "note": "soilwater report writes REPORT.md, tables/, figures/ and studies/ "
                        "here"}) + "\n")
    return folder
