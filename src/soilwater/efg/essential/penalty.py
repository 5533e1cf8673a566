"""The penalty's factors and the round-off level of its forces in an EFG step.

The penalty terms themselves (:func:`soilwater.efg.boundary.penalty_coefficients`) are
:mod:`soilwater.efg.boundary`'s; here are the factors of a run (:func:`factors`) and the
level below which a residual entry carrying a penalty force is round-off
(:func:`roundoff`, :func:`excess`), so that fine grids converge to the tolerance.
"""

import numpy as np

from soilwater.material.regions import Regions


def factors(model, times):
    """Penalty factors: displacement (P-wave modulus / h) and pore pressure (with material
    regions, of the most permeable)."""
    case = model.case
    sc = model.scales
    dt = float(np.max(np.diff(times)))
    k = (max(model.material.permeability) if isinstance(model.material, Regions)
         else case.fluid.permeability)
    flow = (dt * (k / case.fluid.gamma_w) + case.fluid.storage * sc.h**2
            + case.fluid.biot_alpha**2 * sc.h**2 / sc.modulus)
    return {"penalty_alpha_u": case.efg.penalty * sc.modulus / sc.h,
            "penalty_alpha_p": case.efg.penalty * flow / sc.h}


def roundoff(disc, points, du, du_bar, p, plate, alpha_u, alpha_p, rigid_w):
    """Round-off level of the penalty forces in the residual rows, (2n,), (n,) and a float
    (with Nitsche's method, alpha is its beta, some 10^5 times smaller: the level is then
    far below the tolerance).

    A penalty force ``phi^T (alpha w gap)`` has ``alpha`` about ``penalty`` (1e6) times the
    stiffness, and its gap is a difference of displacements (or pressures) of the size of
    the step's increment; in floating point it is then known only to ``eps x sum |terms|``,
    which grows as the spacing shrinks and on fine grids exceeds ``TOLERANCE`` times the
    force scale on the boundary rows, whatever the tangent.
    """
    eps, bc = np.finfo(float).eps, disc.bc
    phi_u, phi_p = disc.boundary_magnitudes
    size = np.abs(points.gap) + phi_u @ np.abs(du) + np.abs(du_bar)                # (G, 2)
    plate_size = (np.abs(points.plate_gap) + phi_u @ np.abs(du[:, 1])
                  + abs(plate - points.plate)) * np.abs(rigid_w)
    force = alpha_u * disc.bp.weights[:, None] * bc.constrained * size
    noise_u = eps * np.concatenate([phi_u.T @ force[:, 0],
                                    phi_u.T @ (force[:, 1] + plate_size)])
    flow = alpha_p * disc.bp.weights * bc.drained * (phi_p @ np.abs(p))
    return noise_u, eps * (phi_p.T @ flow), eps * plate_size.sum()


def excess(R, noise):
    """Largest amount by which ``|R|`` exceeds its round-off level (0 when within it)."""
    return np.max(np.abs(R) - noise, initial=0.0)
