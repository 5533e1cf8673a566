"""Metrics shared by tests, sweeps and the report: paths, ERR, pore-pressure stability,
shear bands.

Stresses are compression positive; every metric states its normalisation.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.references.closed_forms import terzaghi, undrained_pressure
from soilwater.material.driver import run_test
from soilwater.errors import require


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


#: Depth below a column's drained top within which a pore-pressure error belongs to the
#: boundary layer [m]; beyond it, to the interior (the audit's "at least 1 m below").
LAYER = 1.0
#: Interior pollution (over the load) up to which a column rates "good": just above
#: Taylor-Hood's worst first step (0.22 at 3 x 21 nodes, k = 0), the known-good pair.
GOOD = 0.25
#: Interior pollution above which a column rates "bad": the error exceeds the load, as
#: P1/P1's does at k = 0 (1.7 and more), the known-bad pair.
BAD = 1.0


def column_pollution(result, step, layer=LAYER):
    """Boundary-layer overshoot and interior pollution of a column's pore pressure.

    The reference is Terzaghi's series with the initial constrained modulus at the step's
    time (:func:`soilwater.references.closed_forms.terzaghi`), or the undrained pressure
    when k = 0. Every node counts, not only the axis.

    Parameters
    ----------
    result : Result
        A run of a laterally confined column loaded on its drained top.
    step : int
        Output step (1: after the first step).
    layer : float
        Depth of the boundary layer below the top [m].

    Returns
    -------
    overshoot : float
        ``max (p - p_ref)`` within ``layer`` of the top, over the load.
    interior : float
        ``max |p - p_ref|`` deeper than ``layer``, over the load.
    """
    case, snap = result.case, result.snapshots[step]
    y0 = case.nodes()[:, 1]
    p = snap.point_data["p_w"][:len(y0)]
    load = -case.boundary.top.traction[1]
    modulus, fluid = case.material().constrained_modulus(), case.fluid
    if fluid.mobility > 0:
        ref = terzaghi(y0, snap.time, load, case.geometry.height, modulus,
                       fluid.biot_alpha, fluid.storage, fluid.mobility)[0]
    else:
        ref = undrained_pressure(load, modulus, fluid.biot_alpha, fluid.storage)
    error = (p - ref) / load
    near = case.geometry.height - y0 < layer
    return float(error[near].max()), float(np.abs(error[~near]).max())


def rating(interior):
    """``good`` (<= :data:`GOOD`), ``fair`` or ``bad`` (> :data:`BAD`) interior pollution."""
    return "good" if interior <= GOOD else "bad" if interior > BAD else "fair"


#: Time windows of the peer-data README's stability table.
WINDOWS = ((0.0, 0.01), (0.01, 0.1), (0.1, 1.0), (1.0, np.inf))


def terzaghi_errors(result):
    """Pore-pressure and settlement errors of a Terzaghi run against the series solution.

    Pressures at the probes ``p0..p9`` (heights 0..9) are compared with
    :func:`soilwater.references.closed_forms.terzaghi`; errors are normalised by the
    undrained pressure p0 (``max |p - p_exact| / p0``, per time window) and by the load
    (``..._load``).

    Returns
    -------
    dict
        ``window_errors`` {window label: error / p0}, ``max_error_load_after_0.1``,
        ``settlement_error_after_0.1`` (relative), ``overshoot`` (first step,
        ``max p / p0 - 1``).
    """
    from soilwater.references.closed_forms import terzaghi

    case = result.case
    material, fluid = case.material(), case.fluid
    load = -case.boundary.top.traction[1]
    modulus = material.constrained_modulus()
    height = case.geometry.height
    probes = [p for p in case.probes if p.name != "p99"]
    z = np.array([p.point[1] for p in probes])
    h = result.history
    args = (load, height, modulus, fluid.biot_alpha, fluid.storage, fluid.mobility)
    exact = [terzaghi(z, t, *args) for t in h.time]
    p_exact = np.array([e[0] for e in exact])
    settle_exact = np.array([e[1] for e in exact])
    p_h = h[[f"p_w@{p.name}" for p in probes]].to_numpy(float)
    p0 = undrained_pressure(load, modulus, fluid.biot_alpha, fluid.storage)
    err = np.abs(p_h - p_exact).max(axis=1)
    settle = height * (1 - np.exp(-h.eps_a.to_numpy()))
    late = h.time.to_numpy() >= 0.1
    windows = {f"{lo:g} <= t < {hi:g}": float(err[(h.time >= lo) & (h.time < hi)].max() / p0)
               for lo, hi in WINDOWS if ((h.time >= lo) & (h.time < hi)).any()}
    return {"window_errors": windows,
            "max_error_load_after_0.1": float(err[late].max() / load),
            "settlement_error_after_0.1": float(np.abs(settle / settle_exact - 1)[late].max()),
            "overshoot": float(p_h[0].max() / p0 - 1)}


def mandel_errors(result):
    """Centre and mid-width pressures of a Mandel run against the closed form.

    Returns
    -------
    dict
        ``max_error``: ``max |p - p_exact|`` over time at the probes ``centre`` and
        ``mid``, over the undrained pressure ``p0 = F (1 + nu_u)/(3a) = F/(2a)``;
        ``peak_centre`` and ``peak_centre_exact``: the largest centre pressure over p0
        (above 1: the Mandel-Cryer effect).
    """
    from soilwater.references.closed_forms import mandel

    case = result.case
    material = case.material()
    force = -case.plate_force(case.times()[-1])
    a = case.geometry.width
    h = result.history
    x = np.array([dict((p.name, p.point) for p in case.probes)[n][0] for n in ("centre", "mid")])
    exact = np.array([mandel(x, t, force, a, material.G, material.nu, case.fluid.mobility)
                      for t in h.time])
    ours = h[["p_w@centre", "p_w@mid"]].to_numpy(float)
    p0 = force / (2 * a)
    return {"max_error": float(np.abs(ours - exact).max() / p0),
            "peak_centre": float(ours[:, 0].max() / p0),
            "peak_centre_exact": float(exact[:, 0].max() / p0)}


def moose_errors(result, moose):
    """A Terzaghi run against MOOSE's file (peer-data case A), scaled by the load.

    Parameters
    ----------
    result : Result
        A run of the built-in ``terzaghi`` case on MOOSE's time levels.
    moose : pandas.DataFrame
        ``moose_poromech_terzaghi_Q1Q1_consistent.csv`` (load 1).

    Returns
    -------
    dict
        ``pressure_after_0.1``: ``max |p/load - p_moose|`` for t >= 0.1 over p0/load;
        ``settlement_after_0.1``: largest relative settlement difference for t >= 0.1.
    """
    case, h = result.case, result.history
    load = -case.boundary.top.traction[1]
    if not np.allclose(h.time, moose.time, rtol=1e-9):
        raise ValueError("the run is not on MOOSE's time levels")
    columns = [f"p{k}" for k in range(10)]
    p = h[[f"p_w@{c}" for c in columns]].to_numpy(float) / load
    material, fluid = case.material(), case.fluid
    p0 = undrained_pressure(1.0, material.constrained_modulus(), fluid.biot_alpha,
                            fluid.storage)
    late = h.time.to_numpy() >= 0.1
    settle = case.geometry.height * (1 - np.exp(-h.eps_a.to_numpy())) / load
    return {"pressure_after_0.1": float(np.abs(p - moose[columns].to_numpy())[late].max()
                                        / p0),
            "settlement_after_0.1": float(np.abs(settle / -moose.zdisp.to_numpy() - 1)[late]
                                          .max())}


#: A field is localised enough for a band when half its shear strain lies in less than a
#: quarter of the body (localisation 0.5). A strain growing linearly from zero across
#: the body, the steepest smooth variation, has sqrt(2) - 1 = 0.41.
LOCALISED = 0.5
#: The largest width over length (``sqrt`` of the ratio of the principal moments) of the
#: straining zone of a band: at least twice as long as wide. A blob is no band.
SLENDER = 0.5


@dataclass(frozen=True)
class Band:
    """A nodal shear-strain field rated by :func:`band`.

    Attributes
    ----------
    angle : float
        Inclination of the band to the horizontal (x axis) [degrees, 0 to 90; the band
        at -a, its mirror image, counts as a]; NaN where there is no band.
    localisation : float
        ``1 - 2 v``, ``v`` the smallest fraction of the body's area carrying half the
        total shear strain: 0 homogeneous, towards 1 for a thin band.
    aspect : float
        Width over length of the straining zone, ``sqrt(lambda_2 / lambda_1)`` of its
        weighted second moments of position: 0 a line, 1 a disc; NaN without one.
    """

    angle: float
    localisation: float
    aspect: float

    @property
    def found(self):
        """True where the field is a band (:data:`LOCALISED` and :data:`SLENDER`)."""
        return bool(np.isfinite(self.angle))


def band(points, gamma, area=None):
    """Inclination of a shear band in a nodal shear-strain field, and how localised it is.

    The straining zone is the smallest set of nodes (largest ``gamma`` first, by area)
    carrying half the total strain ``sum(area gamma)``; ``gamma_c`` is the strain where
    it ends. Its nodes, weighted by ``area (gamma - gamma_c)``, have a principal-axis fit
    (weighted total least squares line): the band's direction is the axis of the larger
    second moment. The field is a band when :attr:`Band.localisation` is at least
    :data:`LOCALISED` and :attr:`Band.aspect` at most :data:`SLENDER`.

    Parameters
    ----------
    points : array_like, shape (N, 2)
        Node positions [m] (the configuration the angle is measured in).
    gamma : array_like, shape (N,)
        Shear strain at the nodes, >= 0
        (:func:`soilwater.studies.harness.deformation.nodal_strain`).
    area : array_like, shape (N,), optional
        Area each node stands for [m2] (default: equal).

    Returns
    -------
    Band

    Examples
    --------
    A homogeneous field has no band:

    >>> xy = np.stack(np.meshgrid(np.arange(5.0), np.arange(5.0)), -1).reshape(-1, 2)
    >>> rated = band(xy, np.full(25, 0.3))
    >>> rated.found, round(rated.localisation, 12)
    (False, 0.0)
    """
    x = np.asarray(points, float)
    gamma = np.asarray(gamma, float)
    area = np.ones(len(x)) if area is None else np.asarray(area, float)
    require(x.shape == (len(gamma), 2) and area.shape == gamma.shape,
            f"band: points {x.shape}, gamma {gamma.shape} and area {area.shape} must be "
            "(N, 2), (N,) and (N,)")
    order = np.argsort(-gamma, kind="stable")
    g, a = gamma[order], area[order]
    strain = np.concatenate([[0.0], np.cumsum(a * g)])
    if strain[-1] <= 0:
        return Band(float("nan"), 0.0, float("nan"))
    strain /= strain[-1]
    volume = np.concatenate([[0.0], np.cumsum(a)]) / a.sum()
    localisation = float(1 - 2 * np.interp(0.5, strain, volume))
    cut = g[np.searchsorted(strain, 0.5) - 1]
    w = area * np.clip(gamma - cut, 0.0, None)
    if w.sum() <= 0:
        return Band(float("nan"), max(localisation, 0.0), float("nan"))
    centre = w @ x / w.sum()
    d = x - centre
    moments, axes = np.linalg.eigh((w[:, None] * d).T @ d / w.sum())
    aspect = float(np.sqrt(max(moments[0], 0.0) / moments[1]))
    angle = float(np.degrees(np.arctan2(axes[1, 1], axes[0, 1])) % 180.0)
    angle = min(angle, 180.0 - angle)
    found = localisation >= LOCALISED and aspect <= SLENDER
    return Band(angle if found else float("nan"), localisation, aspect)
