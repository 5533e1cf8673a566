"""Result files: written whole or not at all.

A failed run must leave no half-written output and never write NaN, so every writer
goes through a temporary file in the target folder and an atomic rename.
"""

import os
import tempfile
from pathlib import Path

import numpy as np

from soil.errors import SoilwaterError


def write_csv(frame, path):
    """Write a DataFrame to ``path`` atomically, refusing non-finite numbers.

    Parameters
    ----------
    frame : pandas.DataFrame
    path : str or Path

    Raises
    ------
    SoilwaterError
        If a numeric column holds NaN or infinity (nothing is written).
    """
    numbers = frame.select_dtypes("number").to_numpy(dtype=float)
    if not np.isfinite(numbers).all():
        raise SoilwaterError(f"refusing to write {path}: the table holds NaN or infinity")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", newline="") as fh:
            frame.to_csv(fh, index=False)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
