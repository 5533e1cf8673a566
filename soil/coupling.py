"""What both coupled solvers share: scales, tolerances, time marching with cut-backs.

The EFG and FEM solvers differ in how they discretise a step; everything around the step
is here: the initial total stress and the residual scales a step converges against, the
rule that pins the mean pore pressure of a confined undrained body, and the march over the
case's time levels that halves a failing step up to :data:`MAX_CUTS` times.
"""

from dataclasses import dataclass

import numpy as np
import pandas as pd
from tqdm import tqdm

from soil.errors import ConvergenceError
from soil.kinematics import IDENTITY

#: Newton tolerance on the scaled residuals (see :class:`Scales`).
TOLERANCE = 1e-8
MAX_ITERATIONS = 25
#: Halvings of a failing time step before the run stops.
MAX_CUTS = 6


@dataclass(frozen=True)
class Scales:
    """Constants of a coupled run, from the case's initial state.

    Attributes
    ----------
    sigma0 : ndarray, shape (4,)
        Initial total stress ``sigma'_0 - alpha p_w0 I`` (tension positive).
    stress : float
        Stress scale: the largest initial stress or edge traction [kPa].
    modulus : float
        P-wave modulus ``K + 4G/3`` at the initial state [kPa].
    h : float
        Smallest nodal spacing [m].
    pin_pressure : bool
        True for a confined body (no free or rigid component, no drained edge) with
        incompressible constituents: its pore pressure is defined up to a constant, and
        the solvers pin the mean change to zero.

    A step has converged when the displacement residual is below ``TOLERANCE x stress x
    h`` (force per unit thickness) and the continuity residual below ``TOLERANCE x
    stress x h^2 / modulus`` (volume per unit thickness).
    """

    sigma0: np.ndarray
    stress: float
    modulus: float
    h: float
    pin_pressure: bool

    @classmethod
    def of(cls, case, material):
        stress, _ = material.initial_state(1)
        sigma0 = stress[0] - case.fluid.biot_alpha * case.initial_pore_pressure * IDENTITY
        edges = [edge for _, edge in case.boundary.items()]
        tractions = [abs(np.asarray(e.traction, float)).max() for e in edges
                     if e.traction != "exact"]
        free = any({"free", "rigid"} & {e.ux, e.uy} for e in edges)
        pin = case.fluid.storage == 0 and not free and not any(e.drained for e in edges)
        return cls(sigma0, max([abs(stress[0]).max(), *tractions, 1e-12]),
                   float(material.constrained_modulus()), float(min(case.spacing)), pin)

    @property
    def force(self):
        """Residual scale of equilibrium [force per unit thickness]."""
        return self.stress * self.h

    @property
    def volume(self):
        """Residual scale of continuity [volume per unit thickness]."""
        return self.stress * self.h**2 / self.modulus


def march(case, current, step, row, snapshot, stats, progress=True, desc=""):
    """Advance through the case's time levels; cut a failing level back.

    Parameters
    ----------
    case : Case
    current : object
        The solver's state at t = 0.
    step : callable
        ``step(current, t0, t1) -> (current, iterations, residual)``; raises
        :class:`ConvergenceError` (or ``FloatingPointError``) when it fails.
    row : callable
        ``row(current, t, dt, info) -> dict``: the history row of a converged level.
    snapshot : callable
        ``snapshot(current, t) -> Snapshot``.
    stats : dict
        Updated in place: ``newton_iterations``, ``cutbacks``, ``max_residual`` and, when
        the rows carry the uniqueness indicator (``diagnostics.uniqueness``),
        ``uniqueness_onset_step``: the first step (from 1) whose indicator is not
        positive, None if there is none.

    Returns
    -------
    history : pandas.DataFrame
        One row per level; an ``err`` column that is undefined throughout is left empty.
    snapshots : list of Snapshot
        At t = 0 and after every level.
    """
    stats.update({"newton_iterations": 0, "cutbacks": 0, "max_residual": 0.0})
    times = case.times()
    rows, snapshots = [], [snapshot(current, 0.0)]
    for t0, t1 in tqdm(list(zip(times[:-1], times[1:])), desc=desc, unit="step",
                       disable=not progress or None, leave=False):
        current, info = _advance(current, step, t0, t1, stats)
        rows.append(row(current, t1, t1 - t0, info))
        snapshots.append(snapshot(current, t1))
    history = pd.DataFrame(rows)
    if "err" in history and history["err"].isna().all():
        history["err"] = None
    if "uniqueness" in history:
        lost = np.flatnonzero(history["uniqueness"].to_numpy() <= 0)
        stats["uniqueness_onset_step"] = int(lost[0]) + 1 if len(lost) else None
    return history, snapshots


def _advance(current, step, t0, t1, stats):
    """One time level, halved while it fails (up to MAX_CUTS times)."""
    dt = t1 - t0
    for cut in range(MAX_CUTS + 1):
        try:
            t, trial, iterations, residuals = t0, current, 0, []
            for _ in range(2**cut):
                with np.errstate(all="ignore"):  # failures end in ConvergenceError
                    trial, its, res = step(trial, t, t + dt / 2**cut)
                t += dt / 2**cut
                iterations += its
                residuals.append(res)
            stats["cutbacks"] += cut
            stats["newton_iterations"] += iterations
            stats["max_residual"] = max(stats["max_residual"], *residuals)
            return trial, {"iterations": iterations, "residual": max(residuals),
                           "substeps": 2**cut}
        except (ConvergenceError, FloatingPointError) as err:
            reason = err
    raise ConvergenceError(f"step t = {t0:g} -> {t1:g} s failed after {MAX_CUTS} halvings "
                           f"of the time step ({reason}): reduce time steps or loading "
                           "rate, or check the boundary conditions")


def axial_strain(case, heights):
    """``eps_a = -ln(h / H)``: logarithmic axial strain from current top heights [m]."""
    return float(-np.log(np.mean(heights) / case.geometry.height))


def stretching_error(case, d22, weights=None):
    """Paper eq. 1: mean over points of ``|(D22_exact - D22^I) / D22_exact|``.

    ``D22_exact`` is the case's prescribed ``L22``; NaN when it is zero (undefined).
    ``weights`` (e.g. quadrature volumes) turn the mean into a weighted one.
    """
    L22 = case.loading.L[1, 1]
    if L22 == 0:
        return np.nan
    return float(np.average(np.abs((L22 - d22) / L22), weights=weights))
