"""Shared fixtures: the paper's Table 1 clay and the peer-data folder."""

from pathlib import Path

import pytest

from soil.camclay import CamClay

PEER = Path(__file__).resolve().parents[2] / "shared" / "peer-data"


@pytest.fixture
def peer():
    """Folder of the peer reference results (MOOSE, GEOS, MFront/OpenGeoSys)."""
    if not PEER.is_dir():
        pytest.fail(f"peer data not found at {PEER}: the repo must sit beside shared/")
    return PEER


def table1(model="original", ocr=1.0):
    """The paper's Table 1 material."""
    return CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0,
                   model=model, ocr=ocr)
