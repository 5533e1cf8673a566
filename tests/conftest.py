"""Shared fixtures: the paper's Table 1 clay and the peer-data folder."""

import pytest

from soilwater.studies.harness.paths import PEER_DATA
from soilwater.material.camclay import CamClay


@pytest.fixture
def peer():
    """Folder of the peer reference results (MOOSE, GEOS, MFront/OpenGeoSys)."""
    if not PEER_DATA.is_dir():
        pytest.fail(f"peer data not found at {PEER_DATA}: the repo must sit beside shared/")
    return PEER_DATA


def table1(model="original", ocr=1.0):
    """The paper's Table 1 material."""
    return CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0,
                   model=model, ocr=ocr)
