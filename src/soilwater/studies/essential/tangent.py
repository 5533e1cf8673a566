"""The first Newton tangent with penalty or Nitsche's method (``efg.essential``).

* :func:`confined`: how near singular the undrained simple shear's tangent is with
  either method, with and without the pressure stabilisation;
* :func:`conditioning`: the first Newton tangent of a case at a few thousand nodes, its
  displacement block's diagonal span and condition estimate, and restarted GMRES with
  Jacobi or incomplete LU preconditioners: the relative residual it reaches against the
  error of its solution measured against the direct solve.
"""

import itertools

import numpy as np
import pandas as pd
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.studies.harness.runs import solved
from soilwater.efg import solver
from soilwater.efg.discretisation import discretise
from soilwater.efg.system import System
from soilwater.nonlinear.history import TIMERS
from soilwater.case.loader import load_case

#: The values of ``efg.essential`` compared.
METHODS = ("penalty", "nitsche")


def captured(name, overrides):
    """The first Newton system of a case's first step (the tangent the solver factorises).

    Returns
    -------
    K : scipy.sparse.csr_matrix
        The tangent, unknowns ``[du, p_w, plate?, pin?]``.
    R : ndarray
        The residual at the start of the step.
    n : int
        Nodes.
    factor : float
        The displacement condition's factor over ``M/h``: ``alpha_u`` (penalty) or
        ``beta_u`` (Nitsche).
    """
    case = load_case(name, list(overrides))
    model = solver.Model.build(case)
    points = solver._initial_points(model)
    timings = dict.fromkeys(TIMERS, 0.0)
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                              timings)
    system = System(model, points, disc, *case.times()[:2], timings)
    R, _ = system.residual()
    factor = system._factors[0] * model.scales.h / model.scales.modulus
    return sp.csr_matrix(system.tangent()), R, system.n, factor


def confined(methods=METHODS, stabilisations=("none", "perturbation"), small=1e-6):
    """The singular values of the first Newton tangent of the undrained simple shear
    (every edge prescribed, k = 0: the pore pressure is defined up to the constant
    that the mean-pressure multiplier pins), per method and ``efg.stabilisation``.

    Returns
    -------
    pandas.DataFrame
        ``method, stabilisation``, ``condition`` (largest over smallest singular value of
        the tangent with rows and columns scaled by ``|K_ii|^(-1/2)``), ``below`` (how many
        are under ``small`` times the largest), ``smallest`` (the smallest over the
        largest) and ``spread``, max - min of the nodal pore pressure [kPa] after 10
        steps to gamma = 0.06 (exact: uniform, so 0).
    """
    rows = []
    for method, stabilisation in itertools.product(methods, stabilisations):
        overrides = (f"efg.essential={method}", f"efg.stabilisation={stabilisation}")
        K, _, _, _ = captured("simple-shear", overrides)
        run, = solved([("simple-shear", ["time.end=6", "time.steps=10", *overrides])])
        p = run.snapshots[-1].point_data["p_w"]
        d = np.abs(K.diagonal())
        scale = 1 / np.sqrt(np.where(d > 0, d, 1.0))
        values = np.linalg.svd((sp.diags(scale) @ K @ sp.diags(scale)).toarray(),
                               compute_uv=False)
        rows.append({"method": method, "stabilisation": stabilisation,
                     "condition": values[0] / values[-1],
                     "below": int((values < small * values[0]).sum()),
                     "smallest": values[-1] / values[0], "spread": p.max() - p.min()})
    return pd.DataFrame(rows)


#: Cases of :func:`conditioning`, a few thousand nodes each: the consolidating column
#: (rollers, fixed base, drained top) and the unconfined compression (prescribed top).
CONDITIONING_CASES = {
    "terzaghi": ("discretisation.nx=21", "discretisation.ny=101"),
    "unconfined-compression": ("discretisation.layout=grid", "discretisation.nx=41",
                               "discretisation.ny=55"),
}
#: Preconditioners of :func:`conditioning`: label -> factory of ``M ~ K^-1`` from K.
PRECONDITIONERS = {
    "jacobi": lambda K: spla.LinearOperator(K.shape, matvec=lambda x: x / K.diagonal(),
                                            dtype=float),
    "ilu 1e-2": lambda K: _ilu(K, drop_tol=1e-2, fill_factor=5),
    "ilu 1e-4": lambda K: _ilu(K, drop_tol=1e-4, fill_factor=10),
}
#: The systems of :func:`conditioning` and their preconditioners: the whole first Newton
#: system (a saddle point when undrained: no Jacobi) and its displacement block alone
#: with the displacement rows of the residual (the block an AMG cycle would precondition).
SYSTEMS = {"coupled": ("ilu 1e-4",), "u block": ("jacobi", "ilu 1e-2", "ilu 1e-4")}


def conditioning(cases=CONDITIONING_CASES, methods=METHODS, rtols=(1e-3, 1e-6, 1e-9),
                 systems=SYSTEMS, restart=50, maxiter=20):
    """What a Krylov solver sees on the first Newton system of each case.

    Returns
    -------
    summary : pandas.DataFrame
        ``case, method, dofs, diagonal_span`` (largest over smallest ``|K_ii|`` of the
        displacement block), ``condition`` (1-norm estimate of the displacement block,
        :func:`scipy.sparse.linalg.onenormest` of it and of its inverse) and
        ``factor_h_over_M``, the displacement condition's factor (``alpha_u`` or
        ``beta_u``) over ``M/h``.
    krylov : pandas.DataFrame
        ``case, method, system, preconditioner, rtol``, GMRES ``iterations`` (inner,
        restart ``restart``, at most ``maxiter`` restarts), the reached ``residual``
        ``|K x - b| / |b|``, ``error_u`` (max ``|u - u*|`` over max ``|u*|``, u* the
        direct solve), ``error_p`` (the same for p_w, coupled system only) and
        ``converged``.
    """
    summary, krylov = [], []
    for (name, overrides), method in itertools.product(cases.items(), methods):
        K, R, n, factor = captured(name, overrides + (f"efg.essential={method}",))
        Kuu = K[:2 * n, :2 * n].tocsc()
        d = np.abs(Kuu.diagonal())
        summary.append({"case": name, "method": method, "dofs": K.shape[0],
                        "diagonal_span": d.max() / d.min(),
                        "condition": _condition(Kuu), "factor_h_over_M": factor})
        for system, labels in systems.items():
            A, b = (K, -R) if system == "coupled" else (Kuu, -R[:2 * n])
            exact = spla.spsolve(A.tocsc(), b)
            for label, rtol in itertools.product(labels, rtols):
                krylov.append({"case": name, "method": method, "system": system,
                               "preconditioner": label, "rtol": rtol,
                               **_gmres(A, b, n, exact, PRECONDITIONERS[label](A), rtol,
                                        restart, maxiter)})
    return pd.DataFrame(summary), pd.DataFrame(krylov)


def _ilu(K, **options):
    """scipy's incomplete LU of K as a LinearOperator."""
    ilu = spla.spilu(sp.csc_matrix(K), **options)
    return spla.LinearOperator(K.shape, matvec=ilu.solve, dtype=float)


def _condition(A):
    """1-norm condition estimate of a sparse square matrix (its inverse by SuperLU)."""
    lu = spla.splu(A)
    inverse = spla.LinearOperator(A.shape, matvec=lu.solve, rmatvec=lambda x: lu.solve(x, "T"),
                                  dtype=float)
    return float(spla.onenormest(A) * spla.onenormest(inverse))


def _gmres(A, b, n, exact, M, rtol, restart, maxiter):
    """One preconditioned GMRES solve of ``A x = b`` and its errors (:func:`conditioning`):
    the first 2n unknowns are the displacement's, the next n (if any) p_w's."""
    count = [0]

    def inner(_):
        count[0] += 1

    x, info = spla.gmres(A, b, rtol=rtol, restart=restart, maxiter=maxiter, M=M,
                         callback=inner, callback_type="pr_norm")
    u, u_star = x[:2 * n], exact[:2 * n]
    p, p_star = x[2 * n:3 * n], exact[2 * n:3 * n]
    return {"iterations": count[0],
            "residual": float(np.linalg.norm(A @ x - b) / np.linalg.norm(b)),
            "error_u": float(np.abs(u - u_star).max() / np.abs(u_star).max()),
            "error_p": (float(np.abs(p - p_star).max() / np.abs(p_star).max())
                        if len(p) and np.abs(p_star).max() > 0 else np.nan),
            "converged": info == 0}
