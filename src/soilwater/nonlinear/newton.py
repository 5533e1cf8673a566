"""Newton's method on one step of a coupled solver, and the material update it calls.

* :func:`newton`: Newton's method on one step, reusing a factorisation while it
  contracts (:func:`soilwater.linalg.layout.must_refactorise`), each correction halved
  while the material cannot take its iterate;
* :func:`new_counts`: the factorisation counts it keeps;
* :func:`material_update`: kinematics and the material's return mapping at the points.
"""

import numpy as np

from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import factorise, identity
from soilwater.linalg.layout import FORCING_MAX, forcing, must_refactorise
from soilwater.material.kinematics import determinant, inverse, strain_increment
from soilwater.nonlinear.history import timed

#: Newton tolerance on the scaled residuals (see :class:`soilwater.physics.scales.Scales`).
TOLERANCE = 1e-8
MAX_ITERATIONS = 25
#: Whether the first factorisation of a step is the symmetric one of ``sym(K)``
#: (:func:`soilwater.linalg.backends.factorise`; every refactorisation is of ``K``).
#: Off: the tangents are not symmetric enough for it to pay (docs, studies, "Direct solvers").
SYMMETRIC_FIRST = False
#: Halvings of a Newton correction whose iterate the material cannot take.
BACKTRACKS = 4


def new_counts():
    """The factorisation counts :func:`newton` adds to, at zero."""
    return {"factorisations": 0, "symmetric_factorisations": 0, "single_factorisations": 0,
            "perturbed_pivots": 0,
            "factor_flops": 0.0, "linear_iterations": 0}


def newton(system, stats):
    """Newton's method on one step's nonlinear system.

    Modified Newton: a factorisation is kept while each iteration contracts the residual
    (:func:`soilwater.linalg.layout.must_refactorise`), and the current tangent is
    factorised otherwise. With :data:`SYMMETRIC_FIRST` (off by default) the first
    factorisation of the step is the symmetric one of ``sym(K) = (K + K^T) / 2`` (half the
    factor of ``K``'s on PARDISO), kept while it contracts like any other; once a
    factorisation stalls, the step refactorises the full unsymmetric ``K``. The corrections
    of ``sym(K)`` contract the residual at best by the spectral radius of ``sym(K)^-1 (K -
    K^T) / 2``, those of ``K`` by the change of the tangent over the step. SuperLU has no
    symmetric mode: every factorisation is of ``K``.

    With the Krylov back-end a "factorisation" is a preconditioner, and Newton is Newton:
    every iteration assembles the current tangent and hands it to the solver
    (:meth:`soilwater.linalg.krylov.Krylov.adopt`), which keeps the preconditioner of the
    step's first tangent. Each correction is solved inexactly, to the relative residual of
    :func:`soilwater.linalg.layout.forcing` (Eisenstat-Walker): loosely far from the
    solution, tightly near it, and at most the layout's
    :attr:`~soilwater.linalg.layout.Layout.forcing`.

    A correction whose iterate the material or the kinematics cannot take (a return
    mapping that fails, an inverted point) is halved, up to :data:`BACKTRACKS` times
    (:func:`_residual`), before the step fails: past a peak, full Newton's corrections
    can overshoot into such states.

    Parameters
    ----------
    system : object
        The step's unknowns and equations, with

        * ``residual() -> (R, scaled)``: the residual vector at the current iterate and
          its size in units of the tolerance's scales
          (:class:`soilwater.physics.scales.Scales`);
        * ``tangent() -> K``: the sparse Jacobian of ``R`` at the current iterate;
        * ``layout``: what the unknowns are, a :class:`soilwater.linalg.layout.Layout`
          (or None);
        * ``advance(dx)``: add a correction to the unknowns.
    stats : dict
        Added to: ``factorisations`` (all of them), ``symmetric_factorisations`` (those of
        ``sym(K)``), ``single_factorisations`` (those in single precision, PARDISO),
        ``perturbed_pivots`` (summed over the factorisations; PARDISO's
        ``iparm(14)``), ``factor_flops`` (PARDISO's ``iparm(19)``, summed),
        ``linear_iterations`` (Krylov iterations) and ``timings`` (``assembly_s``,
        ``solve_s``); ``linear_solver`` set to the back-end of the last factorisation
        (:func:`soilwater.linalg.backends.identity`).

    Returns
    -------
    iterations : int
        Residual evaluations, the converged one included.
    residual : float
        The converged scaled residual (< :data:`TOLERANCE`).

    Raises
    ------
    ConvergenceError
        No convergence in :data:`MAX_ITERATIONS` iterations.
    FloatingPointError
        A residual that is not finite.

    Examples
    --------
    ``x^2 = 2`` from ``x = 1``; the first factorisation is reused while it contracts the
    residual tenfold per iteration:

    >>> import scipy.sparse as sp
    >>> from soilwater.nonlinear.history import TIMERS
    >>> class Root:
    ...     layout, x = None, np.array([1.0])
    ...     def residual(self):
    ...         return self.x**2 - 2, abs(self.x[0]**2 - 2)
    ...     def tangent(self):
    ...         return sp.csr_matrix(2 * self.x[None])
    ...     def advance(self, dx):
    ...         self.x = self.x + dx
    >>> root, stats = Root(), {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    >>> iterations, residual = newton(root, stats)
    >>> round(float(root.x[0]), 8), stats["factorisations"], bool(residual < TOLERANCE)
    (1.41421356, 2, True)
    """
    cap = FORCING_MAX if system.layout is None else system.layout.forcing
    lu, previous, eta, dx = None, np.inf, cap, None
    for iteration in range(1, MAX_ITERATIONS + 1):
        R, residual = _residual(system, dx)
        if not np.isfinite(residual):
            raise FloatingPointError("the residual is not finite")
        if residual < TOLERANCE:
            return iteration, residual
        if iteration == MAX_ITERATIONS:
            raise ConvergenceError(f"Newton residual {residual:.2e} after {iteration} "
                                   "iterations")
        if must_refactorise(lu, residual, previous) or lu.current:
            first = lu is None
            if not first:
                lu.release()                # one tangent in memory at a time
            with timed(stats["timings"], "assembly_s"):
                K = system.tangent()
            if first or not lu.adopt(K):
                lu = None                   # and one factorisation
                with timed(stats["timings"], "solve_s"):
                    lu = factorise(K, system.layout, symmetric=SYMMETRIC_FIRST and first)
                _count(stats, lu)
            del K                           # the solver holds what it needs
        eta = forcing(residual, previous, eta, TOLERANCE, cap)
        previous, before = residual, (lu.iterations, lu.factorisations, lu.flops)
        with timed(stats["timings"], "solve_s"):
            dx = lu.solve(-R, rtol=eta)
        stats["linear_iterations"] += lu.iterations - before[0]
        stats["factorisations"] += lu.factorisations - before[1]    # redone in double
        stats["factor_flops"] += lu.flops - before[2]
        system.advance(dx)


def _residual(system, dx):
    """``system.residual()`` at the iterate, the last correction ``dx`` halved (up to
    :data:`BACKTRACKS` times) while the iterate is one the material or the kinematics
    cannot take (a :class:`ConvergenceError`: a return mapping that fails, an inverted
    point). If every halving fails, the full correction's error is raised."""
    try:
        return system.residual()
    except ConvergenceError as failure:
        if dx is None:
            raise
        for _ in range(BACKTRACKS):
            dx = dx / 2
            system.advance(-dx)
            try:
                return system.residual()
            except ConvergenceError:
                pass
        raise failure


def _count(stats, lu):
    """Add the factorisation ``lu`` to the counts of :func:`newton`, and name its
    back-end (``linear_solver``, :func:`soilwater.linalg.backends.identity`)."""
    stats["linear_solver"] = identity(lu.backend)
    stats["factorisations"] += lu.factorisations
    stats["symmetric_factorisations"] += lu.symmetric
    stats["single_factorisations"] += lu.single
    stats["perturbed_pivots"] += lu.perturbed_pivots
    stats["factor_flops"] += lu.flops


def material_update(material, stress, state, H, timings, where="an integration point"):
    """Kinematics and the material's return mapping over a step, at many points.

    Parameters
    ----------
    material : Material
    stress, state : ndarray (P, 4), dict
        Effective stress (tension positive) and material state at the start of the step.
    H : ndarray, shape (P, 2, 2)
        ``grad_n(du)``: the step's displacement gradient on the start-of-step
        configuration, ``H[p, i, j] = d du_i / d x_j``.
    timings : dict
        ``material_s`` is added to.
    where : str
        What a point is (``"a node"``, ``"a background cell"``), for the messages of a
        point that inverts or whose return mapping fails.

    Returns
    -------
    stress, state, tangent
        The material's update (:meth:`update`) with the strain and spin increments of
        :func:`soilwater.material.kinematics.strain_increment`.
    J : ndarray, shape (P,)
        ``det F``, ``F = I + H``.
    Finv : ndarray, shape (P, 2, 2)
    deps : ndarray, shape (P, 4)
        The strain increment (Voigt).

    Raises
    ------
    ConvergenceError
        Where ``J <= 0`` (the step inverts ``where``), or the material's update fails
        (its message, with ``where``).
    """
    F = np.eye(2) + H
    J = determinant(F)
    if not np.all(J > 0):
        raise ConvergenceError(f"{where} inverts (J = {J.min():.3g})")
    Finv = inverse(F)
    deps, dw = strain_increment(H, J)
    with timed(timings, "material_s"):
        try:
            stress, state, tangent = material.update(stress, state, deps, dw)
        except ConvergenceError as error:
            raise ConvergenceError(f"{error} (at {where})") from None
    return stress, state, tangent, J, Finv, deps
