"""The linear solver of both coupled solvers (soilwater.linalg): back-ends and reuse."""

import importlib.util

import numpy as np
import pytest
import scipy.sparse as sp

import soilwater.efg.solver
import soilwater.fem.solver
import soilwater.linalg.backends
import soilwater.linalg.pardiso
import soilwater.nonlinear.newton
from soilwater.nonlinear.history import TIMERS
from soilwater.nonlinear.newton import new_counts, newton
from soilwater.errors import ConvergenceError, InputError
from soilwater.linalg.backends import backend, factorise
from soilwater.linalg.layout import Layout
from soilwater.case.loader import load_case

PARDISO = importlib.util.find_spec("pypardiso") is not None


def saddle(n=40, seed=0):
    """An undrained-like u-p matrix: SPD displacement block, zero pressure block."""
    rng = np.random.default_rng(seed)
    a = sp.random(2 * n, 2 * n, density=0.1, random_state=seed)
    A = a @ a.T + sp.eye(2 * n) * 2 * n
    B = sp.random(n, 2 * n, density=0.2, random_state=seed + 1) + sp.eye(n, 2 * n)
    K = sp.bmat([[A, B.T], [B, None]], format="csr")
    groups = np.concatenate([np.arange(n), np.arange(n), np.arange(n)])
    return K, groups, rng.standard_normal(3 * n)


def test_unknown_backend_is_named(monkeypatch):
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "mumps")
    with pytest.raises(InputError, match="SOILWATER_LINEAR_SOLVER"):
        backend()


@pytest.mark.parametrize("name", ["superlu", "pardiso"])
def test_saddle_point_solve(monkeypatch, name):
    if name == "pardiso" and not PARDISO:
        pytest.skip("pypardiso is not installed (extra soilwater[fast])")
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", name)
    K, groups, b = saddle()
    for g in (None, groups):
        x = factorise(K, Layout(groups=g)).solve(b)
        assert np.abs(K @ x - b).max() < 1e-9 * np.abs(b).max()


def unsymmetric_saddle(skew, n=40, seed=0):
    """:func:`saddle` plus ``skew`` times a random skew-symmetric matrix (same pattern)."""
    K, groups, b = saddle(n, seed)
    M = K.copy()
    M.data = np.random.default_rng(seed + 2).uniform(-1.0, 1.0, M.nnz)
    return (K + skew * (M - M.T)).tocsr(), groups, b


@pytest.mark.skipif(not PARDISO, reason="pypardiso is not installed (soilwater[fast])")
@pytest.mark.parametrize("node_blocked", [False, True])
def test_symmetric_factorisation_solves_sym_K(monkeypatch, node_blocked):
    """PARDISO's LDL^T of sym(K) solves the symmetric saddle point (zero pressure block)
    to 1e-9, and an unsymmetric K through its symmetric part, not through K."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "pardiso")
    for skew in (0.0, 0.5):
        K, groups, b = unsymmetric_saddle(skew)
        lu = factorise(K, Layout(groups=groups if node_blocked else None), symmetric=True)
        x = lu.solve(b)
        S = (K + K.T) / 2
        assert lu.symmetric
        assert np.abs(S @ x - b).max() < 1e-9 * np.abs(b).max()
        if skew:
            assert np.abs(K @ x - b).max() > 1e-3 * np.abs(b).max()


def test_superlu_factorises_K_when_asked_for_sym_K(monkeypatch):
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    K, _, b = unsymmetric_saddle(0.5)
    lu = factorise(K, symmetric=True)
    assert not lu.symmetric
    assert np.abs(K @ lu.solve(b) - b).max() < 1e-9 * np.abs(b).max()


class Linear:
    """Newton system ``R(x) = K x - b`` (:func:`soilwater.nonlinear.newton.newton`)."""

    def __init__(self, K, groups, b):
        self.K, self.layout, self.b, self.x = K, Layout(groups=groups), b, np.zeros(len(b))

    def residual(self):
        R = self.K @ self.x - self.b
        return R, np.abs(R).max() / np.abs(self.b).max()

    def tangent(self):
        return self.K

    def advance(self, dx):
        self.x = self.x + dx


@pytest.mark.parametrize("name", ["superlu", "pardiso"])
@pytest.mark.parametrize("skew", [0.0, 0.5])
def test_newton_falls_back_to_K_when_sym_K_stalls(monkeypatch, name, skew):
    """The first factorisation is of sym(K) (PARDISO); with a strongly unsymmetric K its
    correction does not contract, and Newton converges on the factorisation of K."""
    if name == "pardiso" and not PARDISO:
        pytest.skip("pypardiso is not installed (extra soilwater[fast])")
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", name)
    monkeypatch.setattr(soilwater.nonlinear.newton, "SYMMETRIC_FIRST", True)
    system = Linear(*unsymmetric_saddle(skew))
    stats = {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    newton(system, stats)
    symmetric, unsymmetric = {"superlu": (0, 1), "pardiso": (1, int(skew > 0))}[name]
    assert stats["symmetric_factorisations"] == symmetric
    assert stats["factorisations"] == symmetric + unsymmetric


class Fenced:
    """``x^2 = 2`` from ``x = 1`` whose residual, like a return mapping, cannot be
    evaluated from ``x = fence`` on: Newton's first correction lands at 1.5."""

    layout, x, fence = None, np.array([1.0]), 1.45

    def residual(self):
        if self.x[0] >= self.fence:
            raise ConvergenceError("return mapping did not converge")
        return self.x**2 - 2, abs(self.x[0]**2 - 2)

    def tangent(self):
        return sp.csr_matrix(2 * self.x[None])

    def advance(self, dx):
        self.x = self.x + dx


@pytest.mark.parametrize("backtracks, converges", [(4, True), (0, False)])
def test_newton_halves_a_correction_the_material_cannot_take(monkeypatch, backtracks,
                                                             converges):
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    monkeypatch.setattr(soilwater.nonlinear.newton, "BACKTRACKS", backtracks)
    system, stats = Fenced(), {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    if not converges:
        with pytest.raises(ConvergenceError, match="return mapping"):
            newton(system, stats)
        return
    newton(system, stats)
    assert abs(system.x[0] - np.sqrt(2)) < 1e-8


def test_a_first_iterate_the_material_cannot_take_fails_the_step(monkeypatch):
    """Nothing to halve at a step's start: the step fails (and the march cuts it)."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    system = Fenced()
    system.fence = 0.5
    with pytest.raises(ConvergenceError, match="return mapping"):
        newton(system, {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)})


def test_singular_tangent_is_a_convergence_error(monkeypatch):
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    with pytest.raises(ConvergenceError, match="singular"):
        factorise(sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0]])))


def compression(material=None, steps=4):
    case = load_case("unconfined-compression", [f"time.steps={steps}", "time.end=2.0"])
    if material:
        import dataclasses
        case = dataclasses.replace(case, material_spec=material)
    return case


@pytest.mark.parametrize("solve", [soilwater.efg.solver.solve,
                                   lambda c, progress: soilwater.fem.solver.solve(
                                       c, "fem-p1p1", progress=progress)])
def test_elastic_steps_reuse_one_factorisation(monkeypatch, solve):
    """Modified Newton: a linear elastic skeleton needs one factorisation per step."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    elastic = (("model", "elastic"), ("E", 200.0), ("nu", 0.3), ("p0", 3.0))
    result = solve(compression(elastic), progress=False)
    assert result.summary["factorisations"] < result.history.iterations.sum()
    assert result.summary["factorisations"] <= len(result.history) + 1


@pytest.mark.skipif(not PARDISO, reason="pypardiso is not installed (soilwater[fast])")
@pytest.mark.parametrize("symmetric_first", [False, True])
def test_pardiso_and_superlu_give_the_same_steps(monkeypatch, symmetric_first):
    """Both back-ends converge to the same Newton tolerance: EFG Cam-clay paths agree,
    PARDISO's first factorisation of a step of sym(K) or not."""
    runs = {}
    for name in ("superlu", "pardiso"):
        monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", name)
        monkeypatch.setattr(soilwater.nonlinear.newton, "SYMMETRIC_FIRST", symmetric_first)
        result = soilwater.efg.solver.solve(compression(), progress=False)
        runs[name] = result.history
    symmetric = result.summary["symmetric_factorisations"]
    if symmetric_first:
        assert symmetric >= len(result.history)      # one a step, more after a cut-back
    else:
        assert symmetric == 0
    for column in ("p", "q", "eps_a"):
        assert np.allclose(runs["pardiso"][column], runs["superlu"][column],
                           rtol=1e-7, atol=1e-9)


def ill_conditioned(n=60, condition=1e11, seed=0):
    """A dense-pattern sparse matrix with singular values from 1 down to 1/``condition``:
    beyond what a single-precision factor can refine."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    P, _ = np.linalg.qr(rng.standard_normal((n, n)))
    return sp.csr_matrix(Q @ np.diag(np.logspace(0, -np.log10(condition), n)) @ P.T)


@pytest.mark.skipif(not PARDISO, reason="pypardiso is not installed (soilwater[fast])")
@pytest.mark.parametrize("node_blocked", [False, True])
def test_single_precision_factor_refines_to_the_residual_asked_for(monkeypatch,
                                                                   node_blocked):
    """A well-conditioned tangent whose layout asks for it is factorised in single
    precision; each solve is refined in double to a round-off scaled residual, whatever
    the relative residual asked for (modified Newton needs a double factor's solves)."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "pardiso")
    K, groups, b = saddle()
    scales = np.concatenate([np.full(2 * 40, 10.0), np.full(40, 0.1)])
    lu = factorise(K, Layout(groups=groups if node_blocked else None, scales=scales,
                             single=True))
    for rtol in (1e-3, None):
        x = lu.solve(b, rtol=rtol)
        assert lu.single
        assert (np.linalg.norm((K @ x - b) / scales)
                <= soilwater.linalg.pardiso.REFINED * np.linalg.norm(b / scales))
    assert lu.factorisations == 1
    assert not factorise(K, Layout(groups=groups, scales=scales)).single   # a penalty's


@pytest.mark.skipif(not PARDISO, reason="pypardiso is not installed (soilwater[fast])")
@pytest.mark.parametrize("node_blocked", [False, True])
def test_single_precision_factor_too_coarse_is_redone_in_double(monkeypatch, node_blocked):
    """Where refinement does not contract tenfold, the factor is redone in double: the
    solve is then a double factor's, and both factorisations are counted."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "pardiso")
    K = ill_conditioned()
    x_true = np.random.default_rng(1).standard_normal(K.shape[0])
    b = K @ x_true
    groups = np.arange(K.shape[0]) // 3 if node_blocked else None
    lu = factorise(K, Layout(groups=groups, scales=np.ones(K.shape[0]), single=True))
    assert lu.single
    x = lu.solve(b)
    assert not lu.single and lu.factorisations == 2
    assert np.linalg.norm(K @ x - b) <= 1e-9 * np.linalg.norm(b)


@pytest.mark.skipif(not PARDISO, reason="pypardiso is not installed (soilwater[fast])")
@pytest.mark.parametrize("method", ["efg", "fem-th"])
def test_single_precision_takes_the_steps_of_double(monkeypatch, method):
    """Solves refined to round-off on a single-precision factor (Nitsche EFG stabilised,
    fem-th: their layouts ask for it) take the Newton iterations and factorisations of a
    double factor, and its path."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "pardiso")
    case = load_case("unconfined-compression", ["time.steps=4", "time.end=2.0",
                                                'efg.essential="nitsche"',
                                                'efg.stabilisation="perturbation"'])
    runs = {}
    for single in (False, True):
        monkeypatch.setattr(soilwater.linalg.backends, "SINGLE", single)
        result = (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
                  else soilwater.fem.solver.solve(case, method, progress=False))
        runs[single] = result
    assert runs[True].summary["single_factorisations"] > 0
    assert runs[False].summary["single_factorisations"] == 0
    for key in ("newton_iterations", "factorisations"):
        assert runs[True].summary[key] == runs[False].summary[key]
    for column in ("p", "q", "eps_a"):
        assert np.allclose(runs[True].history[column], runs[False].history[column],
                           rtol=1e-7, atol=1e-9)
