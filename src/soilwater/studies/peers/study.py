"""Single-point peer data (``../shared/peer-data``) rerun through the stress-point driver.

Each function returns a row-by-row DataFrame, the reference beside ours, so that tests
assert on it and the report tabulates it. Our material is the closest variant, not the
peer's exact law: hypoelastic ``K = v p'/kappa`` with a constant shear modulus.
"""

from pathlib import Path

import numpy as np
import pandas as pd

from soilwater.material.camclay import CamClay
from soilwater.material.driver import Segment, integrate, run_test
from soilwater.studies.harness.paths import PEER_DATA

#: Where the peer files sit when the repository is checked out beside ``shared/``.


def geos_oedometer(folder=PEER_DATA):
    """GEOS modified Cam-clay oedometer, load/unload/reload (peer-data case C).

    ``kappa = C_r v0`` and ``lambda = C_c v0`` give ``K = p'/C_r`` as in GEOS; the shear
    modulus is GEOS's constant mu = 5e7 Pa; p'0 = 1e5 Pa, OCR 1.5, M = 1.2.

    Returns
    -------
    pandas.DataFrame
        ``t, eps_a`` and ``axial, radial, pc`` [Pa, compression positive] with their
        ``*_ref`` (no p'c in the GEOS file: ``pc_ref`` is absent).
    """
    data = np.loadtxt(Path(folder) / "geos_mcc_oedometric_triaxialdriver.txt")
    v0 = 2.0
    clay = CamClay(lam=0.003 * v0, kappa=0.002 * v0, M=1.2, nu=0.25, e0=v0 - 1, p0=1e5,
                   ocr=1.5, model="modified", G=5e7)
    ours = run_test(clay, "oedometer", 0.006, points=len(data) - 1)
    return pd.DataFrame({
        "t": data[:, 0], "eps_a": ours.eps_a, "eps_a_ref": -data[:, 1],
        "axial": ours.p + 2 / 3 * ours.q, "axial_ref": -data[:, 4],
        "radial": ours.p - 1 / 3 * ours.q, "radial_ref": -data[:, 5],
        "pc": ours.pc,
    })


def mfront_triaxial(folder=PEER_DATA):
    """MFront/OpenGeoSys modified Cam-clay, stress-controlled drained triaxial (case B).

    Started from the file's state at t = 0.02 (isotropic 2e5 Pa, p'c and v as printed);
    the axial stress (their z, our y) is ramped as in the file, lateral stress held. Our
    shear modulus is their ``E/(2(1 + nu))``; our bulk modulus is ``v p'/kappa`` (theirs is
    constant), so the nearly elastic start differs most. Strains are increments from
    t = 0.02; ours are logarithmic (time integrals of D), as the MFront law's volume update
    implies.

    Returns
    -------
    pandas.DataFrame
        ``t``, ``eps_axial``, ``eps_lateral`` (tension positive) and ``pc`` [Pa], each with
        ``*_ref``.
    """
    ref = pd.read_csv(Path(folder) / "mfront_ogs_mcc_drained_triax.ref", comment="#",
                      sep=r"\s+", header=None).to_numpy()
    start = int(np.argmin(np.abs(ref[:, 0] - 0.02)))
    row, ref = ref[start], ref[start:]
    clay = CamClay(lam=0.077, kappa=0.0066, M=1.2, nu=0.3, e0=row[23] - 1, p0=2e5,
                   ocr=row[20] / 2e5, model="modified", G=52e6 / 2.6)
    duration = ref[-1, 0] - row[0]
    seg = Segment(duration, stress_control=(True, True, True, False),
                  stress_rate=(0.0, (ref[-1, 9] - row[9]) / duration, 0.0, 0.0))
    ours = integrate(clay, row[[7, 9, 8, 10]], {"pc": row[20], "v": row[23]}, [seg],
                     points_per_segment=len(ref) - 1)
    return pd.DataFrame({
        "t": ours.t + row[0], "t_ref": ref[:, 0],
        "eps_axial": ours.eyy, "eps_axial_ref": ref[:, 3] - row[3],
        "eps_lateral": ours.exx, "eps_lateral_ref": ref[:, 1] - row[1],
        "pc": ours.pc, "pc_ref": ref[:, 20],
    })


def relative_difference(frame, column, floor=0.0):
    """``|ours - ref| / max(|ref|, floor)`` for one column of a peer table."""
    ref = frame[f"{column}_ref"].abs().clip(lower=max(floor, 1e-300))
    return (frame[column] - frame[f"{column}_ref"]).abs() / ref


def summary(folder=PEER_DATA):
    """Largest relative differences by quantity and time window, both peer cases."""
    geos, mfront = geos_oedometer(folder), mfront_triaxial(folder)
    rows = []
    for col in ("axial", "radial"):
        rows.append(("GEOS oedometer (case C)", f"{col} stress", "all",
                     relative_difference(geos, col).max(), 0.03))
    for lo, hi in ((0.02, 0.2), (0.2, 0.8), (0.8, 1.0)):
        window = mfront[(mfront.t > lo + 1e-9) & (mfront.t <= hi + 1e-9)]
        tol = 0.05 if (lo, hi) == (0.2, 0.8) else np.nan
        rows.append(("MFront/OGS triaxial (case B)", "axial strain", f"{lo} < t <= {hi}",
                     relative_difference(window, "eps_axial").max(), tol))
        rows.append(("MFront/OGS triaxial (case B)", "p'c", f"{lo} < t <= {hi}",
                     relative_difference(window, "pc").max(), 0.02 if hi <= 0.8 else np.nan))
    return pd.DataFrame(rows, columns=["peer", "quantity", "window", "max_rel_diff",
                                       "tolerance"])
