"""Where the studies read and write: the source checkout they run from.

The studies (``soilwater report``, ``check``, ``bench``) run from a source checkout: they
write ``reports/`` and ``.cache/`` at its root and read the peers' data from
``../shared/peer-data`` beside it.
"""

from pathlib import Path

#: The installed ``soilwater`` package folder.
PACKAGE = Path(__file__).resolve().parents[2]
#: The source checkout: ``src/soilwater`` lies two levels below it.
ROOT = PACKAGE.parents[1]
#: Cached runs of :mod:`soilwater.studies.harness.runner`.
CACHE = ROOT / ".cache" / "runs"
#: Regression tables of ``soilwater check``.
REFERENCE = ROOT / "reports" / "reference"
#: The peers' results (MOOSE, GEOS, OpenGeoSys/MFront).
PEER_DATA = ROOT.parent / "shared" / "peer-data"
