"""MOOSE's Terzaghi file from the peers' data, read by the consolidation study and by
``soilwater check``."""

from pathlib import Path

import pandas as pd

from soilwater.studies.harness.paths import PEER_DATA


def moose_terzaghi(folder=PEER_DATA):
    """MOOSE's consistent Q1/Q1 Terzaghi file (peer-data case A): time, p0..p9, p99, zdisp."""
    return pd.read_csv(Path(folder) / "moose_poromech_terzaghi_Q1Q1_consistent.csv")
