"""Where the studies read and write: the source checkout they run from.

The studies (``soilwater report``, ``check``, ``bench``) run from a source checkout: they
write ``reports/`` and ``.cache/`` at its root (the cache elsewhere with
``SOILWATER_CACHE``, :func:`cache_folder`) and read the peers' data from
``../shared/peer-data`` beside it.
"""

import os
from pathlib import Path

#: The installed ``soilwater`` package folder.
PACKAGE = Path(__file__).resolve().parents[2]
#: The source checkout: ``src/soilwater`` lies two levels below it.
ROOT = PACKAGE.parents[1]
#: Regression tables of ``soilwater check``.
REFERENCE = ROOT / "reports" / "reference"
#: The peers' results (MOOSE, GEOS, OpenGeoSys/MFront).
PEER_DATA = ROOT.parent / "shared" / "peer-data"


def cache_folder():
    """The folder of the cached runs of :mod:`soilwater.studies.harness.runner`:
    ``SOILWATER_CACHE`` when set (a shared file system, or a cache copied between
    machines; ``soilwater report --cache DIR`` sets it), else ``.cache/runs`` in the
    checkout. Read at each call, so a change takes effect for the next sweep."""
    given = os.environ.get("SOILWATER_CACHE", "").strip()
    return Path(given).expanduser() if given else ROOT / ".cache" / "runs"
