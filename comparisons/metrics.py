"""Metrics shared by tests, sweeps and the report: paths, ERR, pore-pressure stability.

Stresses are compression positive; every metric states its normalisation.
"""

import numpy as np

from soil.driver import run_test


def path_error(history, material, test="undrained-plane-strain"):
    """Largest distance of a run's (p', q) from the stress-point driver at equal strain.

    Parameters
    ----------
    history : pandas.DataFrame
        A run's history (``eps_a`` or, for simple shear, ``gamma``; ``p``, ``q``).
    material : CamClay
    test : str
        The driver test with the same stretching.

    Returns
    -------
    float
        ``max_steps max(|p - p_d|, |q - q_d|) / p'0``.
    """
    strain = history["gamma"] if test == "undrained-simple-shear" else history["eps_a"]
    driver = run_test(material, test, float(strain.max()), points=2000)
    p = np.interp(strain, driver.eps_a, driver.p)
    q = np.interp(strain, driver.eps_a, driver.q)
    return float(max(np.abs(history.p - p).max(), np.abs(history.q - q).max()) / material.p0)


def axis_profile(result, step):
    """p_w at the nodes of the column's axis at output ``step``, base to top.

    The axis is the column of nodes nearest to ``x = width/2`` in the initial
    configuration. Returns heights (current, m) and p_w.
    """
    case = result.case
    x0 = case.nodes()[:, 0]
    axis = np.abs(x0 - x0[np.argmin(np.abs(x0 - case.geometry.width / 2))]) < 1e-9
    snap = result.snapshots[step]
    y = snap.points[axis, 1]
    order = np.argsort(y)
    return y[order], snap.point_data["p_w"][axis][order]


def oscillation_index(p, load):
    """Total variation of a profile in excess of a monotone one, over the load.

    ``(sum |p_(i+1) - p_i| - |p_end - p_start|) / load``: zero for a monotone profile
    (the reference solutions of the column are monotone in depth), positive for any
    wiggle.
    """
    p = np.asarray(p, dtype=float)
    return float((np.abs(np.diff(p)).sum() - abs(p[-1] - p[0])) / load)


def overshoot(p, reference):
    """``max(p) / reference - 1``: how far the largest pore pressure exceeds the reference."""
    return float(np.max(p) / reference - 1.0)
