"""Self-weight and the initial state of a case: the buoyant weight and the geostatic start.

Gravity g acts along -y (``[gravity]``). The pore pressure unknown p_w is then the pore
pressure in excess of hydrostatic, the water table at or above the top surface: drained
boundaries hold p_w = 0 and the reported p_w is the excess. With Biot alpha = 1 the
hydrostatic pressure and the weight of the water balance the buoyancy of the solids, and
the skeleton carries the buoyant unit weight

    ``gamma' = gamma_sat - gamma_w = (Gs - 1) gamma_w (g / G_N) / (1 + e)``  [kN/m3]

(``gamma_sat = (Gs + e) gamma_w / (1 + e)``, gamma_w quoted at standard gravity G_N). The
solids' mass is conserved (``v = 1 + e`` grows as ``J``), so gamma' times the current
volume is its start-of-step value times the start-of-step volume: on the configuration
x_n of the updated-Lagrangian step it is a dead load, with no tangent.

The initial state (``[initial]``) is uniform (the material's p'0, e0 and ocr at every
point), the gravity start (:mod:`soilwater.nonlinear.gravity_start`: the uniform state
loaded by its self-weight before t = 0, run by the solvers; here it is the uniform state
it starts from) or geostatic: the vertical effective stress ``sigma'_v`` of the buoyant
weight under the surcharge, integrated down from the top with the void ratio of each
depth (``d sigma'_v / d depth = gamma'(e(sigma'_v))``), ``sigma'_h = sigma'_zz = k0
sigma'_v``, and the state on the material's compression line: for Cam-clay p'c of the
normally consolidated state at ``ocr sigma'_v`` and the specific volume of
:meth:`soilwater.material.camclay.CamClay.volume` on the material's line
(:attr:`soilwater.material.camclay.CamClay.anchor`: ``material.e_ref`` under
``sigma_v_ref``, or its e0 at p'0). A linear elastic skeleton
keeps its e0. Tension is positive in the stresses, as everywhere.
"""

from functools import lru_cache

import numpy as np
from scipy.integrate import solve_ivp

from soilwater.errors import InputError
from soilwater.material.kinematics import IDENTITY
from soilwater.material.regions import Regions

#: Standard gravity [m/s2]: gamma_w is a unit weight at G_N.
G_N = 9.81


def buoyant_weight(case, v):
    """``gamma' = (Gs - 1) gamma_w (g / G_N) / v`` [kN/m3] at specific volumes v (0 without
    gravity)."""
    fluid = case.fluid
    return (fluid.specific_gravity - 1) * fluid.gamma_w * case.gravity.g / G_N / np.asarray(v)


def initial_state(case, material, points):
    """Effective stress (P, 4) and material state at t = 0 (the pore pressure is
    ``case.initial_pore_pressure`` everywhere); for a gravity start, the uniform state its
    self-weight is switched on from (:mod:`soilwater.nonlinear.gravity_start`).

    Parameters
    ----------
    case : Case
    material : Material
        ``case.material()``.
    points : ndarray, shape (P, 2)
        Positions in the initial configuration [m].
    """
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    uniform = case.initial.stress != "geostatic"
    if isinstance(material, Regions):
        region = case.geometry.region_of(points)
        if uniform:
            return material.initial_state(len(points), region=region)
        sigma_v = _vertical_stress(case)(case.geometry.height - points[:, 1])
        return material.gather([_geostatic(case, m, sigma_v[region == r]) for r, m in
                                enumerate(material.materials)], region)
    if uniform:
        return material.initial_state(len(points))
    return _geostatic(case, material, _vertical_stress(case)(case.geometry.height
                                                             - points[:, 1]))


def total_stress(case, material, points):
    """Initial total stress ``sigma'_0 - alpha p_w0 I`` (P, 4) at initial positions [kPa]
    (:func:`initial_state`'s: the uniform one of a gravity start, whose boundary load it
    stays)."""
    stress, _ = initial_state(case, material, points)
    return stress - case.fluid.biot_alpha * case.initial_pore_pressure * IDENTITY


def k0(case, material):
    """The geostatic ``sigma'_h / sigma'_v``: ``initial.k0``, or the material's normally
    consolidated value."""
    value = case.initial.k0
    return material.k0_nc() if value == "nc" else value


def normal_void_ratio(material, sigma_v):
    """Void ratio of the normally consolidated one-dimensional state at ``sigma'_v`` [kPa]
    on the material's compression line (Cam-clay,
    :attr:`soilwater.material.camclay.CamClay.anchor`): the line a geostatic start
    lies on.

    Examples
    --------
    >>> from soilwater.case.loader import load_case
    >>> case = load_case("large-strain-column")
    >>> round(float(normal_void_ratio(case.material(), 10.0)), 12)
    2.4
    """
    nc = material.k0_nc()
    sigma_v = np.asarray(sigma_v, dtype=float)
    return material.volume((1 + 2 * nc) / 3 * sigma_v, _normal_size(material, sigma_v),
                           material.anchor) - 1


def _geostatic(case, material, sigma_v):
    """Stress and state at vertical effective stresses ``sigma_v`` [kPa] (compression
    positive)."""
    ratio = k0(case, material)
    stress = -sigma_v[:, None] * np.array([ratio, 1.0, ratio, 0.0])
    if not material.plastic:
        return stress, {"v": np.full(len(sigma_v), 1 + material.e0)}
    p, q = (1 + 2 * ratio) / 3 * sigma_v, abs(1 - ratio) * sigma_v
    pc = _normal_size(material, case.initial.ocr * sigma_v)
    state = {"pc": pc, "v": material.volume(p, pc, material.anchor)}
    if np.any(material.yield_value(stress, state) > 1e-9):
        raise InputError(f"initial.k0 = {case.initial.k0} puts the geostatic stress outside "
                         f"the yield surface of ocr = {case.initial.ocr}: use a k0 nearer "
                         f"the normally consolidated {material.k0_nc():.3f}, or a larger ocr")
    return stress, state


def _normal_size(material, sigma_v):
    """p'c of the normally consolidated one-dimensional state at ``sigma'_v``."""
    nc = material.k0_nc()
    return material.size((1 + 2 * nc) / 3 * sigma_v, (1 - nc) * sigma_v)


@lru_cache(maxsize=16)
def _vertical_stress(case):
    """``depth -> sigma'_v`` [kPa] of a geostatic start: the buoyant weight integrated
    from the surcharge at the top, each depth's void ratio from its own stress (and its
    own layer's material: the regions met down the middle of a mesh,
    :meth:`soilwater.geometry.mesh.Mesh.layers`)."""
    material, height = case.material(), case.geometry.height
    layers = [(height, 0.0, material)]
    if isinstance(material, Regions):
        layers = [(top, bottom, material.materials[r])
                  for top, bottom, r in case.geometry.mesh.layers()]
    pieces, start = [], case.initial.surcharge
    for top, bottom, layer in layers:
        pieces.append((height - top, _layer(case, layer, start, top - bottom)))
        start = float(pieces[-1][1](top - bottom))

    def sigma_v(depth):
        depth = np.clip(np.asarray(depth, float), 0.0, height)
        k = np.searchsorted([d for d, _ in pieces], depth, side="right") - 1
        out = np.empty(depth.shape)
        for i, (d, piece) in enumerate(pieces):
            at = k == i
            if at.any():
                out[at] = piece(depth[at] - d)
        return out
    return sigma_v


def _layer(case, material, top, thickness):
    """``depth below the layer's top -> sigma'_v`` [kPa] in one layer of ``material``
    under ``top`` [kPa]."""
    def weight(sigma_v):
        _, state = _geostatic(case, material, np.atleast_1d(sigma_v))
        return buoyant_weight(case, state["v"])

    if not material.plastic or case.gravity.g == 0:
        slope = float(weight(top)[0])
        return lambda depth: top + slope * np.asarray(depth)
    sol = solve_ivp(lambda d, s: weight(s), (0.0, thickness), [top], dense_output=True,
                    rtol=1e-11, atol=1e-12 * max(top, 1.0))
    return lambda depth: sol.sol(np.clip(depth, 0.0, thickness))[0]
