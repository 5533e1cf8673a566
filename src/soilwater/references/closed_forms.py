"""Closed-form solutions used as boundary data and as references (plane strain).

Each solution is a function of current coordinates returning displacement (N, 2) and
Cauchy stress (N, 4) as ``(xx, yy, zz, xy)``, tension positive, in the case's units.
Cases name one in their ``[exact]`` table (``solution = "..."`` plus its parameters), and
boundary components marked ``exact`` take their displacement or traction from it.
"""

import numpy as np

from soilwater.errors import InputError


def linear_field(points, E, nu, gradient=((1e-3, 2e-3), (-1e-3, 5e-4)), offset=(1e-3, -2e-3)):
    """The patch test field ``u = offset + gradient x`` and its constant stress.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    E, nu : float
        Young's modulus and Poisson ratio (plane strain).
    gradient : 2 x 2 nested sequence
        Displacement gradient ``du_i/dx_j``.
    offset : 2 sequence
        Rigid translation.
    """
    G = np.asarray(gradient, dtype=float)
    u = np.asarray(offset, dtype=float) + points @ G.T
    eps = np.array([G[0, 0], G[1, 1], 0.0, G[0, 1] + G[1, 0]])
    stress = plane_strain_stiffness(E, nu) @ eps
    return u, np.broadcast_to(stress, (len(points), 4)).copy()


def timoshenko_beam(points, E, nu, P, length, depth):
    """Cantilever under an end shear load, plane strain (Timoshenko and Goodier).

    The beam occupies ``[0, length] x [0, depth]``, its axis at ``y = depth/2``; it is
    clamped (exact displacements) at ``x = 0`` and carries a parabolic shear traction of
    resultant ``P`` (upward for P > 0) at ``x = length``. Plane strain uses the plane-stress
    formulas with ``E/(1 - nu^2)`` and ``nu/(1 - nu)``.

    Returns
    -------
    u : ndarray, shape (N, 2)
    stress : ndarray, shape (N, 4)
    """
    Eb, nb = E / (1 - nu**2), nu / (1 - nu)
    x, y = points[:, 0], points[:, 1] - depth / 2
    L, D = length, depth
    inertia = D**3 / 12
    ux = -P * y / (6 * Eb * inertia) * ((6 * L - 3 * x) * x + (2 + nb) * (y**2 - D**2 / 4))
    uy = P / (6 * Eb * inertia) * (3 * nb * y**2 * (L - x) + (4 + 5 * nb) * D**2 * x / 4
                                   + (3 * L - x) * x**2)
    sxx = -P * (L - x) * y / inertia
    sxy = P / (2 * inertia) * (D**2 / 4 - y**2)
    stress = np.stack([sxx, 0 * x, nu * sxx, sxy], axis=1)
    return np.stack([ux, uy], axis=1), stress


def plane_strain_stiffness(E, nu):
    """Elastic tangent (4, 4) from Voigt strain ``(xx, yy, zz, 2xy)`` to stress."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    C = lam * np.outer([1, 1, 1, 0], [1, 1, 1, 0]) + 2 * mu * np.diag([1, 1, 1, 0.5])
    return C


def strain_from_stress(stress, E, nu):
    """Voigt strain of a plane-strain stress (inverse of :func:`plane_strain_stiffness`)."""
    return np.linalg.solve(plane_strain_stiffness(E, nu), np.asarray(stress).T).T


#: Solutions a case can name in ``[exact] solution = ...``.
SOLUTIONS = {"linear": linear_field, "timoshenko-beam": timoshenko_beam}


def exact_solution(name, **parameters):
    """A function ``points -> (u, stress)`` for a named solution and its parameters."""
    if name not in SOLUTIONS:
        raise InputError(f"exact.solution = {name!r} is unknown: use one of "
                         f"{', '.join(SOLUTIONS)}")

    def field(points):
        return SOLUTIONS[name](np.asarray(points, dtype=float), **parameters)

    return field


def terzaghi(z, t, load, height, modulus, alpha, storage, mobility, terms=200):
    """Terzaghi consolidation of a column drained at the top (z measured from the base).

    Parameters
    ----------
    z : array_like
        Heights above the impermeable base [m].
    t : float
        Time since the step load [s] (> 0).
    load : float
        Compressive load on the top (> 0) [stress unit].
    height : float
        Column height h [m].
    modulus : float
        Constrained (oedometric) modulus ``1/m_v = K + 4G/3``.
    alpha, storage : float
        Biot coefficient and storage S = 1/M.
    mobility : float
        ``k / gamma_w``.

    Returns
    -------
    p : ndarray
        Pore pressure (compression positive) at z.
    settlement : float
        Downward displacement of the top (positive).
    """
    mv = 1.0 / modulus
    cv = mobility / (storage + alpha**2 * mv)
    p0 = undrained_pressure(load, modulus, alpha, storage)
    k = np.arange(1, terms + 1)[:, None]
    m = (2 * k - 1) * np.pi / (2 * height)
    decay = np.exp(-(m**2) * cv * t)
    z = np.atleast_1d(np.asarray(z, dtype=float))[None, :]
    p = 4 * p0 / np.pi * np.sum((-1.0) ** (k - 1) / (2 * k - 1) * np.cos(m * z) * decay, 0)
    U = 1 - 8 / np.pi**2 * np.sum(decay[:, 0] / (2 * k[:, 0] - 1) ** 2)
    u0 = load * mv * height * storage / (storage + alpha**2 * mv)
    u_inf = load * mv * height
    return p, u0 + U * (u_inf - u0)


def xie_leo(depth, t, load, height, mv, permeability, gamma_w, drained_bottom=False,
            terms=400):
    """Large-strain consolidation of a homogeneous layer (Xie and Leo 2004).

    Gibson's finite-strain equation has a closed form when the volume compressibility
    ``mv = -de/dsigma' / (1 + e)`` is constant and ``k / (1 + e)^2`` is constant
    (``k = k0 ((1 + e)/(1 + e0))^2``): ``w = exp(mv u)`` then obeys the linear diffusion
    equation in the initial (Lagrangian) depth ``a`` with ``cv = k0 / (gamma_w mv)``.
    After a step ``load`` on a layer drained at the top (u = 0 at a = 0):

        u(a, t) = ln(1 + (exp(mv q) - 1) sum_m (2/M) sin(M a/H) exp(-M^2 Tv)) / mv,
        S(t) = H (1 - exp(-mv q)) (1 - sum_m (2/M^2) exp(-M^2 Tv)),

    ``M = (2m + 1) pi / 2``, ``Tv = cv t / H^2``: the degree of settlement is Terzaghi's,
    the final settlement ``H (1 - exp(-mv q))`` and the pore pressure lags Terzaghi's.
    A base that also drains halves the drainage path (H/2, symmetric about mid-depth).
    Xie, K. H. and Leo, C. J. (2004), Computers and Geotechnics 31, 301-314, eqs. for a
    uniform e0 (their self-weight variant needs ``k0`` at each depth's initial state).

    Parameters
    ----------
    depth : array_like
        Initial depth a below the top [m] (0 <= a <= height).
    t : float
        Time since the step [s] (> 0).
    load : float
        Step increase of the effective stress the layer will carry [kPa] (> 0).
    height : float
        Initial height H [m].
    mv : float
        Volume compressibility [1/kPa].
    permeability : float
        k0 at the initial void ratio [m/s].
    gamma_w : float
        Unit weight of water [kN/m3].
    drained_bottom : bool
        Double drainage.

    Returns
    -------
    u : ndarray
        Excess pore pressure [kPa] (compression positive) at ``depth``.
    settlement : float
        Fall of the top [m] (positive down).

    Examples
    --------
    The final settlement of a layer 10 m high with mv q = 0.3:

    >>> u, s = xie_leo([5.0], 1e12, 300.0, 10.0, 1e-3, 1e-8, 9.81)
    >>> round(float(s), 4), round(float(u[0]), 6)
    (2.5918, 0.0)
    """
    path = height / 2 if drained_bottom else height
    a = np.atleast_1d(np.asarray(depth, dtype=float))[None, :]
    a = np.where(a > path, height - a, a)
    M = ((2 * np.arange(terms) + 1) * np.pi / 2)[:, None]
    Tv = permeability / (gamma_w * mv) * t / path**2
    decay = np.exp(-(M**2) * Tv)
    series = np.sum(2 / M * np.sin(M * a / path) * decay, axis=0)
    u = np.log1p(np.expm1(mv * load) * series) / mv
    degree = 1 - np.sum(2 / M[:, 0] ** 2 * decay[:, 0])
    return u, height * -np.expm1(-mv * load) * degree


def undrained_pressure(load, modulus, alpha, storage):
    """Pore pressure of a laterally confined layer right after a step load (Terzaghi's
    initial condition): ``alpha m_v load / (S + alpha^2 m_v)``, ``m_v = 1 / modulus``.

    Parameters
    ----------
    load : float
        Compressive vertical load (> 0) [stress unit].
    modulus : float
        Constrained modulus ``K + 4G/3`` of the skeleton.
    alpha, storage : float
        Biot coefficient and storage S = 1/M.

    Examples
    --------
    >>> undrained_pressure(10.0, 100.0, 1.0, 0.0)
    10.0
    """
    mv = 1.0 / modulus
    return alpha * mv * load / (storage + alpha**2 * mv)


def mandel(x, t, force, a, G, nu, mobility, terms=100):
    """Mandel's problem: pore pressure under a rigid frictionless plate, plane strain.

    Incompressible constituents (Biot alpha = 1, S = 0, so B = 1 and nu_u = 1/2); a
    specimen ``2a`` wide, drained at ``x = +-a``; ``force`` is the compressive force on
    the plate per unit thickness over the half-width ``a``.

    Parameters
    ----------
    x : array_like
        Distance from the centre line [m].
    t : float
        Time since loading [s] (> 0).

    Returns
    -------
    ndarray
        Pore pressure (compression positive); at ``t = 0+`` it is ``force/(2a)``
        everywhere, and at the centre it first rises above that (Mandel-Cryer effect).
    """
    nu_u = 0.5
    c = mobility * 2 * G * (1 - nu) / (1 - 2 * nu)
    roots = mandel_roots((1 - nu) / (nu_u - nu), terms)[:, None]
    x = np.atleast_1d(np.asarray(x, dtype=float))[None, :]
    series = (np.sin(roots) / (roots - np.sin(roots) * np.cos(roots))
              * (np.cos(roots * x / a) - np.cos(roots)) * np.exp(-roots**2 * c * t / a**2))
    return 2 * force * (1 + nu_u) / (3 * a) * series.sum(axis=0)


def mandel_roots(ratio, terms):
    """The first positive roots of ``tan(r) = ratio r`` (one in each branch of tan)."""
    from scipy.optimize import brentq

    def f(r):
        return np.sin(r) - ratio * r * np.cos(r)

    eps = 1e-12
    return np.array([brentq(f, k * np.pi + eps, k * np.pi + np.pi / 2 - eps)
                     if k else brentq(f, eps * 1e3, np.pi / 2 - eps) for k in range(terms)])


def undrained_strength(clay):
    """Undrained strength ``s_u = M p'_f / sqrt(3)`` of a Cam-clay in plane strain [kPa].

    At constant volume the critical state is reached at ``p'_f = p'0 (OCR / r)^Lambda``
    whatever the path, ``r = e`` for the original model and 2 for the modified one
    (``Lambda = (lambda - kappa) / lambda``; normally consolidated: ``p'0 exp(-Lambda)``
    and ``p'0 2^-Lambda``). In plane strain at critical state the out-of-plane stress is
    the in-plane mean, so the largest in-plane shear stress is ``q / sqrt(3)``.

    Parameters
    ----------
    clay : soilwater.material.camclay.CamClay

    Examples
    --------
    The paper's Table 1 clay (original model, normally consolidated, p'0 = 3 kPa):

    >>> from soilwater.material.camclay import CamClay
    >>> clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
    >>> round(float(undrained_strength(clay)), 4)
    1.3016
    """
    r = np.e if clay.model == "original" else 2.0
    return clay.M * clay.p0 * (clay.ocr / r) ** clay.Lambda / np.sqrt(3)


#: Prandtl's bearing capacity factor of a weightless Tresca soil: the limit pressure
#: under a rigid strip footing, rough or smooth, is ``PRANDTL x s_u``.
PRANDTL = 2 + np.pi


def flamant_settlement(force, G, nu, ratio):
    """Extra settlement of a line load when the elastic body under it grows ``ratio``-fold
    [m]: ``force (1 - nu) ln(ratio) / (pi G)``.

    Flamant's line load ``force`` [kN/m] on an elastic half-plane in plane strain moves
    the surface by ``-(force (1 - nu) / (pi G)) ln r + C`` at distance r; C is fixed
    where the body is held, so a footing's settlement relative to a base at depth D
    grows as ``ln D`` without bound. Doubling a domain whose far field is elastic adds
    ``force (1 - nu) ln 2 / (pi G)`` to the settlement at a given load, whatever happens
    near the footing.

    Parameters
    ----------
    force : float or ndarray
        Line load [kN/m per unit thickness], the whole footing's (both symmetry halves).
    G, nu : float
        Shear modulus [kPa] and Poisson's ratio of the far field.
    ratio : float
        Size of the larger domain over the smaller one.

    Examples
    --------
    >>> round(float(flamant_settlement(6.69, 51.6, 0.333, 2.0)), 5)
    0.01908
    """
    return np.asarray(force) * (1 - nu) * np.log(ratio) / (np.pi * G)


def surface_load_pressure(x, z, xs, qs):
    """Undrained excess pore pressure [kPa] under a surface pressure on an incompressible
    elastic half-plane, the load symmetric about x = 0.

    In plane strain the stresses of a surface load on a homogeneous half-plane do not
    depend on the elastic constants, and ``sigma_x + sigma_z`` is the harmonic function
    that is ``-2 q`` on the loaded surface (Poisson's integral); undrained with
    incompressible constituents (nu_u = 1/2, B = 1), the pore pressure takes the mean total
    stress, ``p_w = -(sigma_x + sigma_z) / 2``:

    ``p_w(x, z) = (1/pi) int q(s) z / ((x - s)^2 + z^2) ds``,

    here with q piecewise linear through ``(xs, qs)`` for ``s >= 0``, mirrored to ``s <
    0``, zero beyond ``xs[-1]``: integrated in closed form on each piece. Under the middle
    of a uniform strip of half-width b it is ``(2 q / pi) atan(b / z)``.

    Parameters
    ----------
    x, z : array_like
        Horizontal position and depth below the surface [m] (z > 0).
    xs, qs : array_like
        The load's profile from the axis: positions [m], increasing from 0, and the
        pressure there [kPa, compression positive].

    Examples
    --------
    >>> b, z = 5.0, 2.0
    >>> round(float(surface_load_pressure(0.0, z, [0.0, b], [100.0, 100.0])), 6)
    75.776212
    >>> round(float(2 * 100 / np.pi * np.arctan(b / z)), 6)
    75.776212
    """
    x, z = np.asarray(x, float)[..., None], np.asarray(z, float)[..., None]
    xs, qs = np.asarray(xs, float), np.asarray(qs, float)
    a, b, qa, qb = xs[:-1], xs[1:], qs[:-1], qs[1:]
    slope = (qb - qa) / (b - a)

    def piece(lo, hi, q0, c, x):          # int (q0 + c (s - lo)) z / ((x - s)^2 + z^2) ds
        def F(s):                         # antiderivative in t = s - x
            t = s - x
            return (q0 + c * (x - lo)) * np.arctan(t / z) + c * z / 2 * np.log(t**2 + z**2)
        return F(hi) - F(lo)

    right = piece(a, b, qa, slope, x)
    left = piece(a, b, qa, slope, -x)     # the mirror image: s -> -s
    return (right + left).sum(axis=-1) / np.pi


def undrained_poisson(material, fluid):
    """Undrained Poisson's ratio of a skeleton with its pore fluid, at the initial state:
    ``(3 K_u - 2 G) / (2 (3 K_u + G))`` with ``K_u = K + alpha^2 / S`` (1/2 when the
    constituents are incompressible, S = 0).

    Parameters
    ----------
    material : soilwater.material.protocol.Material
    fluid : soilwater.material.fluid.Fluid
        ``biot_alpha`` and ``storage`` S [1/kPa].

    Examples
    --------
    >>> from soilwater.material.elastic import LinearElastic
    >>> from soilwater.material.fluid import Fluid
    >>> undrained_poisson(LinearElastic(E=100.0, nu=0.25), Fluid(storage=0.0))
    0.5
    >>> round(undrained_poisson(LinearElastic(E=100.0, nu=0.25), Fluid(storage=1e9)), 6)
    0.25
    """
    K, G = (float(m) for m in material.moduli())
    if fluid.storage == 0:
        return 0.5
    Ku = K + fluid.biot_alpha**2 / fluid.storage
    return (3 * Ku - 2 * G) / (2 * (3 * Ku + G))


def self_weight_settlement(weight, height, modulus):
    """Settlement [m, positive down] of a laterally confined hypoelastic layer on a fixed
    base under its own buoyant weight, drained to equilibrium, at finite strain.

    The Jaumann rate with constant constrained modulus M gives, with no rotation, a
    vertical Cauchy stress ``M ln(lambda)`` (lambda the vertical stretch); the weight
    above a particle at initial height Y is ``weight (H - Y)`` per unit area (weight per
    initial volume, conserved), so ``lambda = exp(-weight (H - Y) / M)`` and the
    settlement ``int (1 - lambda) dY = H - (M / weight)(1 - exp(-weight H / M))``; to
    first order the small-strain ``weight H^2 / (2 M)``.

    Parameters
    ----------
    weight : float
        Buoyant unit weight in the initial state [kN/m3].
    height : float
        Initial height H [m].
    modulus : float
        Constrained modulus ``M = K + 4G/3`` [kPa].

    Examples
    --------
    >>> a = self_weight_settlement(8.0, 10.0, 1e4)
    >>> round(a, 6), round(8.0 * 10.0**2 / (2 * 1e4), 6)
    (0.039894, 0.04)
    """
    a = weight * height / modulus
    return float(height * (1 - (-np.expm1(-a)) / a))
