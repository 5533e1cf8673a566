"""The report's two resolutions: full (the studies as the report states them) and quick
(``soilwater report --quick``: every study coarser, a first look in minutes).

The resolution is fixed when the process starts: ``SOILWATER_QUICK=1`` in the
environment (``soilwater report --quick`` sets it before it imports a study) makes it
quick. A study picks each of its sizes once, when it is imported, with :func:`pick`, so
that its runs, tables, figures and section all read the same sizes. Every page and figure
of a quick report carries :data:`LABEL`.
"""

import os

#: The environment variable that makes a process's studies quick (``1``).
VARIABLE = "SOILWATER_QUICK"

#: The words every page and figure of a quick report carries.
LABEL = ("QUICK REPORT: reduced resolution, a first look; `make report` gives the full "
         "one")


def active():
    """True in a process making the quick report."""
    return os.environ.get(VARIABLE, "").strip() == "1"


def pick(full, quick):
    """``quick`` in a process making the quick report, else ``full``."""
    return quick if active() else full
