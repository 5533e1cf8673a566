"""Stress-point driver: a material under a prescribed velocity-gradient history.

This is the paper's "theoretical solution": the rate equations (Jaumann rate of stress
= continuum elastoplastic tangent : D) are integrated with an adaptive Runge-Kutta
method (``scipy.integrate.solve_ivp``, DOP853) to tight tolerance, a route independent of
the return mapping in :meth:`soilwater.material.camclay.CamClay.update`. Elastic and plastic phases
are separated by events (first yield, unloading), so the discontinuity of the tangent is
never stepped over.

A loading program is a list of :class:`Segment`; each component of the stretching
``(xx, yy, zz, 2xy)`` is either strain controlled (its rate prescribed) or stress
controlled (the rate of the matching stress component prescribed; the strain rate is
solved for). The axial direction of the named tests is y. Reported strains are
logarithmic (the time integral of D), compression positive; for simple shear the
column ``eps_a`` holds the engineering shear strain ``gamma = L_xy t``.
"""

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from soilwater.errors import InputError, require
from soilwater.material.kinematics import invariants


@dataclass(frozen=True)
class Segment:
    """One stage of a loading program, with constant rates.

    Parameters
    ----------
    duration : float
        Length of the stage [time].
    strain_rate : tuple of 4 floats
        Prescribed stretching ``(D_xx, D_yy, D_zz, 2 D_xy)`` on strain-controlled
        components (ignored on stress-controlled ones).
    stress_control : tuple of 4 bools
        Which components are stress controlled.
    stress_rate : tuple of 4 floats
        Prescribed Jaumann-free stress rates on stress-controlled components.
    spin : float
        In-plane spin ``W_xy``.
    """

    duration: float
    strain_rate: tuple = (0.0, 0.0, 0.0, 0.0)
    stress_control: tuple = (False, False, False, False)
    stress_rate: tuple = (0.0, 0.0, 0.0, 0.0)
    spin: float = 0.0


@dataclass
class _Point:
    """ODE state ``y = (stress[4], pc, v, strain[4])`` and its helpers."""

    material: object
    segment: Segment
    plastic: bool = False
    controlled: np.ndarray = field(init=False)

    def __post_init__(self):
        self.controlled = np.asarray(self.segment.stress_control, dtype=bool)

    def kinematics(self, y, plastic):
        """Stretching D, stress rate and plastic multiplier rate at state y."""
        stress, state = y[:4], {"pc": y[4], "v": y[5]}
        seg = self.segment
        D = np.array(seg.strain_rate, dtype=float)
        Ce, N, H, theta_fp = self.material.rates(stress, state, D)
        C = elastoplastic(Ce, N, H) if plastic else Ce
        w = seg.spin
        spin_term = np.array([2 * w * stress[3], -2 * w * stress[3], 0.0,
                              w * (stress[1] - stress[0])])
        u = self.controlled
        if u.any():
            rhs = np.asarray(seg.stress_rate)[u] - spin_term[u] - C[np.ix_(u, ~u)] @ D[~u]
            D[u] = np.linalg.solve(C[np.ix_(u, u)], rhs)
        dgamma = (N @ Ce @ D) / (N @ Ce @ N + H) if plastic else 0.0
        return D, C @ D + spin_term, dgamma, theta_fp

    def rhs(self, t, y):
        D, dstress, dgamma, theta_fp = self.kinematics(y, self.plastic)
        return np.concatenate([dstress, [y[4] * theta_fp * dgamma, y[5] * D[:3].sum()], D])

    def yield_event(self, t, y):
        return self.material.yield_value(y[None, :4], {"pc": y[4:5]})[0]

    def unload_event(self, t, y):
        return self.kinematics(y, True)[2]

    def loading(self, y):
        """Whether the point at y, on the yield surface, loads plastically."""
        return self.yield_event(0, y) > -1e-9 and self.unload_event(0, y) > 0


def elastoplastic(Ce, N, H):
    """Continuum elastoplastic tangent ``Ce - (Ce N)(N Ce) / (N Ce N + H)`` (Voigt, 4 x 4)
    from :meth:`soilwater.material.camclay.CamClay.rates`: Jaumann stress rate = tangent @ D."""
    return Ce - np.outer(Ce @ N, N @ Ce) / (N @ Ce @ N + H)


def tangents(material, raw, segment):
    """The continuum tangent at every row of a path from :func:`integrate`, (R, 4, 4).

    Rows on the yield surface that load under the segment's stretching get the
    elastoplastic tangent, the others the elastic one; a loop over the path's rows (a
    driver path, not a hot path).
    """
    point = _Point(material, segment)
    D = np.asarray(segment.strain_rate, float)
    out = []
    for y in raw[["sxx", "syy", "szz", "sxy", "pc", "v"]].to_numpy():
        Ce, N, H, _ = material.rates(y[:4], {"pc": y[4], "v": y[5]}, D)
        out.append(elastoplastic(Ce, N, H) if point.loading(np.append(y, np.zeros(4)))
                   else Ce)
    return np.array(out)


def integrate(material, stress, state, segments, points_per_segment=100, rtol=1e-10):
    """Integrate a material point through a loading program.

    Parameters
    ----------
    material : CamClay or LinearElastic
        Anything with ``rates`` and ``yield_value`` (Cam-clay); elastic materials have no
        yield surface and are not driven here.
    stress : array_like, shape (4,)
        Initial Cauchy effective stress, tension positive.
    state : dict
        Initial ``pc`` and ``v``.
    segments : list of Segment
    points_per_segment : int
        Output points per segment (equally spaced in time, end points included).
    rtol : float
        Relative tolerance of the integrator.

    Returns
    -------
    pandas.DataFrame
        Columns ``t, sxx, syy, szz, sxy, pc, v, exx, eyy, ezz, gxy`` (strains logarithmic,
        tension positive, as integrals of D).
    """
    y = np.concatenate([np.asarray(stress, float), [state["pc"], state["v"]], np.zeros(4)])
    scale = np.concatenate([np.full(4, abs(state["pc"])), [abs(state["pc"]), 1.0], np.ones(4)])
    t0, rows = 0.0, [np.concatenate([[0.0], y])]
    for seg in segments:
        require(seg.duration > 0, f"driver segment duration {seg.duration} must be positive")
        t_out = np.linspace(t0, t0 + seg.duration, points_per_segment + 1)[1:]
        point = _Point(material, seg)
        point.plastic = point.loading(y)
        t = t0
        while t < t_out[-1]:
            event = _event(point.unload_event if point.plastic else point.yield_event,
                           -1 if point.plastic else 1)
            sol = solve_ivp(point.rhs, (t, t_out[-1]), y, method="DOP853", rtol=rtol,
                            atol=1e-12 * scale, events=event, dense_output=True)
            if sol.status == -1:
                raise InputError(f"stress-point driver failed: {sol.message}")
            mask = (t_out > t) & (t_out <= sol.t[-1])
            rows += [np.concatenate([[tt], sol.sol(tt)]) for tt in t_out[mask]]
            t, y = sol.t[-1], sol.y[:, -1]
            if sol.status == 1:  # an event: switch between elastic and plastic
                point.plastic = not point.plastic
        t0 = t_out[-1]
    columns = ["t", "sxx", "syy", "szz", "sxy", "pc", "v", "exx", "eyy", "ezz", "gxy"]
    return pd.DataFrame(rows, columns=columns)


def _event(fun, direction):
    """A terminal solve_ivp event crossing zero in ``direction``."""
    def event(t, y):
        return fun(t, y)
    event.terminal, event.direction = True, direction
    return event


# -- named tests -------------------------------------------------------------------------
_FREE_LATERAL = (True, False, True, False)


def _program(test, strain):
    """Segments of a named test, with unit rate, reaching ``strain`` (see TESTS)."""
    if test == "undrained-plane-strain":
        return [Segment(strain, (1.0, -1.0, 0.0, 0.0))]
    if test == "undrained-simple-shear":
        return [Segment(strain, (0.0, 0.0, 0.0, 1.0), spin=0.5)]
    if test == "undrained-triaxial":
        return [Segment(strain, (0.5, -1.0, 0.5, 0.0))]
    if test == "drained-triaxial":
        return [Segment(strain, (0.0, -1.0, 0.0, 0.0), stress_control=_FREE_LATERAL)]
    if test == "isotropic":
        return [Segment(3 * strain, (-1 / 3, -1 / 3, -1 / 3, 0.0))]
    if test == "oedometer":  # the GEOS load/unload/reload program, scaled to `strain`
        levels = np.array([0.0, 4, 2, 5, 3, 6]) / 6 * strain
        return [Segment(abs(b - a), (0.0, -np.sign(b - a), 0.0, 0.0))
                for a, b in zip(levels[:-1], levels[1:])]
    raise InputError(f"unknown driver test {test!r}: use one of {', '.join(TESTS)}")


#: Named tests of ``soilwater path`` with a one-line description each.
TESTS = {
    "undrained-plane-strain": "isochoric plane strain: D_yy = -D_xx compressive, D_zz = 0 "
                              "(the paper's uniform unconfined compression)",
    "undrained-simple-shear": "simple shear L_xy = rate (spin W_xy = rate/2), isochoric",
    "undrained-triaxial": "isochoric axisymmetric compression: D_xx = D_zz = -D_yy/2",
    "drained-triaxial": "axial compression D_yy, constant lateral stress (sxx, szz)",
    "isotropic": "isotropic compression, D = -rate/3 I; eps_a = eps_v/3",
    "oedometer": "K0 loading, unloading and reloading: axial strain through "
                 "4/6, 2/6, 5/6, 3/6 and 1 of the target, lateral strain zero",
}


#: The largest controlling strain of :func:`run_test` (logarithmic).
MAX_STRAIN = 5.0


def run_test(material, test, strain, points=200):
    """Run a named test to ``strain`` and return the ``soilwater path`` table.

    Parameters
    ----------
    material : CamClay
    test : str
        One of :data:`TESTS`.
    strain : float
        Final controlling strain (axial compression, or shear strain for simple shear),
        positive.
    points : int
        Output rows after the initial one (spread over the segments), >= 1.

    Returns
    -------
    pandas.DataFrame
        Columns ``step, eps_a, eps_v, p, q, pc`` (compression positive).

    Raises
    ------
    InputError
        For ``points`` < 1, a strain outside (0, :data:`MAX_STRAIN`], or one that would
        compress the void ratio of an isotropic or oedometer test to zero.

    Examples
    --------
    >>> from soilwater.material.camclay import CamClay
    >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
    >>> table = run_test(clay, "undrained-plane-strain", 0.05, points=10)
    >>> list(table.columns)
    ['step', 'eps_a', 'eps_v', 'p', 'q', 'pc']
    """
    raw, _ = _integrated(material, test, strain, points)
    return path_table(raw, shear=(test == "undrained-simple-shear"))


def _integrated(material, test, strain, points):
    """A named test from the material's initial state: the raw path of :func:`integrate`
    (``points`` rows spread over the segments) and the segments."""
    require(isinstance(points, (int, np.integer)) and points >= 1,
            f"--points {points} must be a whole number >= 1 (output rows)")
    require(np.isfinite(strain) and 0 < strain <= MAX_STRAIN,
            f"--strain {strain} must be > 0 and <= {MAX_STRAIN:g} (a logarithmic strain: "
            f"{MAX_STRAIN:g} shortens a specimen to {100 * np.exp(-MAX_STRAIN):.1f} % of its "
            "height)")
    volumetric = {"isotropic": 3 * strain, "oedometer": strain}.get(test, 0.0)
    e0 = getattr(material, "e0", None)
    require(e0 is None or volumetric < np.log1p(e0),
            f"--strain {strain} compresses the {test} specimen to a volumetric strain of "
            f"{volumetric:g}, past ln(1 + e0) = {np.log1p(e0 or 0):.3g} where the void ratio "
            f"reaches 0: give a strain below {np.log1p(e0 or 0) * strain / max(volumetric, 1e-300):.3g}")
    segments = _program(test, strain)
    stress, state = material.initial_state(1)
    raw = integrate(material, stress[0], {k: v[0] for k, v in state.items()}, segments,
                    points_per_segment=max(1, points // len(segments)))
    return raw, segments


def continuum_path(material, test, strain, points=200):
    """A named test's raw path (:func:`integrate`) and the continuum tangent at each row.

    Returns
    -------
    raw : pandas.DataFrame
        As :func:`integrate`.
    tangents : ndarray, shape (R, 4, 4)
        :func:`tangents` of the rows under the first segment's stretching.
    """
    raw, segments = _integrated(material, test, strain, points)
    require(len(segments) == 1, f"test {test!r} has {len(segments)} segments; the "
            "continuum path takes a single-segment test")
    return raw, tangents(material, raw, segments[0])


def closed_form_q(clay, p):
    """Undrained q at p' on the plastic part of a path from isotropic p'0.

    Original Cam-clay (normally consolidated): ``q/(M p') = ln(p'0/p') / Lambda``;
    modified: ``p'/p'0 = [OCR M^2/(M^2 + eta^2)]^Lambda`` solved for ``q = eta p'``.
    ``Lambda = (lambda - kappa)/lambda``; p' and q compression positive.

    Examples
    --------
    >>> from soilwater.material.camclay import CamClay
    >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
    >>> p_failure = 3.0 * np.exp(-clay.Lambda)
    >>> round(float(closed_form_q(clay, p_failure) / (clay.M * p_failure)), 12)
    1.0
    """
    M, L = clay.M, clay.Lambda
    if clay.model == "original":
        return M * p * np.log(clay.p0 / p) / L
    return p * np.sqrt(M**2 * (clay.ocr * (clay.p0 / p) ** (1 / L) - 1))


#: Columns of the ``soilwater path`` table (:func:`path_table`).
PATH_COLUMNS = ("step", "eps_a", "eps_v", "p", "q", "pc")


def path_table(raw, shear=False):
    """Reduce a raw :func:`integrate` table to :data:`PATH_COLUMNS`."""
    p, q = invariants(raw[["sxx", "syy", "szz", "sxy"]].to_numpy())
    return pd.DataFrame({
        "step": np.arange(len(raw)),
        "eps_a": (raw["gxy"] if shear else -raw["eyy"]).to_numpy() + 0.0,
        "eps_v": 0.0 - (raw["exx"] + raw["eyy"] + raw["ezz"]).to_numpy(),
        "p": p, "q": q, "pc": raw["pc"].to_numpy(),
    })
