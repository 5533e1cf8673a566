"""The iterative back-end (soilwater.linalg.krylov, ``SOILWATER_LINEAR_SOLVER=krylov``): its solves
reach the tolerance they are asked for, and a run through it converges to the direct
solver's history to the Newton tolerance."""

import numpy as np
import pytest
import scipy.sparse as sp

import soilwater.efg.solver
import soilwater.fem.solver
from soilwater.studies.bench.plan import compression
from soilwater.errors import InputError
from soilwater.linalg.krylov_amg import amg
from soilwater.linalg.krylov_schwarz import Schwarz, subdomains
import soilwater.efg.system
import soilwater.linalg.backends
import soilwater.nonlinear.newton
from soilwater.linalg.backends import backend, factorise, linear_solver
from soilwater.linalg.layout import Layout
from soilwater.case.loader import load_case

pytest.importorskip("pyamg")


def biot(n=12, dt=1e-3, storage=0.0):
    """A P1/P1-like u-p matrix on an n x n grid: an elastic block ``A`` (5-point
    Laplacians on both components), the divergence coupling ``B`` and the continuity
    block ``-(storage M + dt L)``; rows scaled as the solvers scale them."""
    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    L = sp.kronsum(one, one).tocsr()
    grad = sp.diags([-0.5, 0.5], [-1, 1], shape=(n, n))
    Gx, Gy = sp.kron(sp.eye(n), grad), sp.kron(grad, sp.eye(n))
    A = sp.block_diag([L, L]) * 3.0 + sp.bmat([[Gx.T @ Gx, Gx.T @ Gy],
                                                [Gy.T @ Gx, Gy.T @ Gy]]) * 2.0
    B = sp.vstack([Gx.T, Gy.T])
    D = -(storage * sp.eye(n * n) + dt * L)
    K = sp.bmat([[A, B], [B.T, D]], format="csr")
    xy = np.column_stack([c.ravel() for c in np.meshgrid(np.arange(n), np.arange(n))])
    m = n * n
    layout = Layout(groups=np.tile(np.arange(m), 3), fields=np.repeat([0, 1, 2], m),
                    locations=np.tile(xy, (3, 1)).astype(float), scales=np.ones(3 * m),
                    mass=sp.diags(np.concatenate([np.zeros(2 * m), np.ones(m)])), modulus=3.0)
    return K, layout


@pytest.mark.parametrize("dt", [0.0, 1e-3, 1.0])
@pytest.mark.parametrize("rtol", [1e-3, 1e-9])
def test_solve_reaches_the_tolerance_asked_for(monkeypatch, dt, rtol):
    """Down to k = 0 (dt = 0: a zero pressure block but for the Dirichlet-free grid's
    compressibility) the relative residual is at most rtol, and at 1e-9 the solution is
    the direct one's."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "krylov")
    K, layout = biot(dt=dt, storage=1e-3)
    b = np.random.default_rng(1).standard_normal(K.shape[0])
    solver = factorise(K, layout)
    x = solver.solve(b, rtol=rtol)
    assert np.linalg.norm(K @ x - b) <= 1.01 * rtol * np.linalg.norm(b)
    assert 0 < solver.iterations < 200
    if rtol < 1e-6:
        exact = sp.linalg.spsolve(K.tocsc(), b)
        assert np.abs(x - exact).max() < 1e-6 * np.abs(exact).max()


def test_an_adopted_tangent_is_solved_with_the_kept_preconditioner(monkeypatch):
    """After ``adopt(K2)`` the solves are of K2 (a later Newton tangent), through the
    preconditioner built from the first."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "krylov")
    K, layout = biot(dt=1e-2)
    K2 = K + sp.diags(np.linspace(0.0, 0.5, K.shape[0]) * (layout.fields < 2))
    solver = factorise(K, layout)
    assert solver.current and solver.adopt(K2)
    b = np.random.default_rng(3).standard_normal(K.shape[0])
    x = solver.solve(b, rtol=1e-9)
    assert np.linalg.norm(K2 @ x - b) <= 1.01e-9 * np.linalg.norm(b)
    assert np.linalg.norm(K @ x - b) > 1e-3 * np.linalg.norm(b)


def test_preconditioner_repeats_and_leaves_the_random_stream(monkeypatch):
    """pyamg's setup draws ``np.random`` vectors (its spectral-radius estimates): two
    preconditioners of one tangent apply alike, and the caller's random stream goes on as
    if no setup had drawn from it. Unseeded, they differed, and so did a run's FGMRES
    count: 96858 to 279804 in five runs of fem-th's unconfined compression (Gauss-Seidel
    smoother)."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "krylov")
    K, layout = biot(n=30, dt=1e-2)
    np.random.seed(1)
    first = factorise(K, layout)
    drawn = np.random.rand()
    second = factorise(K, layout)
    np.random.seed(1)
    assert np.random.rand() == drawn
    r = np.random.default_rng(4).standard_normal(K.shape[0])
    assert np.allclose(first._apply(r), second._apply(r), rtol=1e-12, atol=0.0)


def test_bordered_unknowns_are_eliminated(monkeypatch):
    """A plate-like unknown coupled to many rows (field -1) is solved with the rest."""
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "krylov")
    K, layout = biot(dt=1e-2)
    n = K.shape[0]
    e = np.zeros(n)
    e[1:n // 3:2] = 1.0                                # all y displacements of a row
    K = sp.bmat([[K, sp.csr_matrix(e[:, None])], [sp.csr_matrix(e[None]), None]],
                format="csr")
    layout = Layout(groups=np.append(layout.groups, -1), fields=np.append(layout.fields, -1),
                    locations=np.vstack([layout.locations, [0.0, 0.0]]),
                    scales=np.ones(n + 1), mass=sp.block_diag([layout.mass, [[0.0]]]), modulus=3.0)
    b = np.random.default_rng(2).standard_normal(n + 1)
    x = factorise(K, layout).solve(b, rtol=1e-10)
    assert np.linalg.norm(K @ x - b) <= 1.01e-10 * np.linalg.norm(b)


def test_schwarz_subdomains_cover_every_unknown_and_keep_their_inverses():
    """The overlapping subdomains of a smoothed-aggregation hierarchy hold every unknown
    (some in two), each sorted, the kept block inverses are those of ``A``'s blocks, and
    a sweep is multiplicative Schwarz on ``A`` (from the kept rows), both to the single
    precision they are kept in (``INVERSES``, ``ROWS``)."""
    import pyamg

    K, layout = biot(n=20)
    A = sp.csr_matrix(K[:800, :800])
    ml = pyamg.smoothed_aggregation_solver(sp.bsr_matrix(A, blocksize=(2, 2)),
                                           max_coarse=10, keep=True)
    smoother = Schwarz(A, *subdomains(ml.levels[0].C, ml.levels[0].AggOp, 2))
    sub, ptr = smoother.subdomain, smoother.pointer
    inv, inv_ptr = smoother.inverses, smoother.inverse_pointer
    assert set(sub) == set(range(800)) and len(sub) > 800
    for i in range(len(ptr) - 1):
        dofs = sub[ptr[i]:ptr[i + 1]]
        assert np.all(np.diff(dofs) > 0)
        block = A[dofs][:, dofs].toarray()
        inverse = inv[inv_ptr[i]:inv_ptr[i + 1]].reshape(len(dofs), len(dofs))
        assert inverse.dtype == np.float32
        assert np.allclose(inverse @ block, np.eye(len(dofs)), atol=1e-5)
    b, swept, expected = np.random.default_rng(1).standard_normal(800), np.zeros(800), np.zeros(800)
    smoother.forward(A, swept, b)
    for i in range(len(ptr) - 1):
        dofs = sub[ptr[i]:ptr[i + 1]]
        expected[dofs] += np.linalg.solve(A[dofs][:, dofs].toarray(), (b - A @ expected)[dofs])
    assert np.allclose(swept, expected, rtol=1e-5, atol=1e-5 * np.abs(expected).max())


def test_schwarz_solves_side_by_side_only_subdomains_that_do_not_touch(monkeypatch):
    """The subdomain ranges a Schwarz sweep solves side by side are independent: none
    writes an unknown another range reads (its rows' columns) or writes. So a sweep on
    the pool of threads gives exactly the sweep of one thread."""
    import pyamg

    import soilwater.linalg.krylov_schwarz

    K, layout = biot(n=20)
    A = sp.csr_matrix(K[:800, :800])
    ml = pyamg.smoothed_aggregation_solver(sp.bsr_matrix(A, blocksize=(2, 2)),
                                           max_coarse=10, keep=True)
    # split even this small one
    monkeypatch.setattr(soilwater.linalg.krylov_schwarz, "SPLIT_FROM", 0)
    monkeypatch.setattr(soilwater.linalg.krylov_schwarz, "SIDE_BY_SIDE_FROM", 0)
    smoother = Schwarz(A, *subdomains(ml.levels[0].C, ml.levels[0].AggOp, 2))
    sub, ptr = smoother.subdomain, smoother.pointer
    assert (len(smoother.runs) > 1
            and len(smoother.runs[0]) == soilwater.linalg.krylov_schwarz.GROUPS)
    for ranges in smoother.runs:
        rows = [sub[ptr[lo]:ptr[hi]] for lo, hi in ranges]
        reads = [set(A[r].indices) | set(r) for r in rows]
        for i, written in enumerate(rows):
            assert all(set(written).isdisjoint(read) for j, read in enumerate(reads) if j != i)
    b = np.random.default_rng(0).standard_normal(800)
    together, alone = np.zeros(800), np.zeros(800)
    smoother.forward(A, together, b)
    smoother.backward(A, together, b)
    monkeypatch.setattr(soilwater.linalg.krylov_schwarz, "run",
                        lambda kernel, ranges: [kernel(*r) for r in ranges])
    smoother.forward(A, alone, b)
    smoother.backward(A, alone, b)
    assert np.array_equal(together, alone)


def test_schwarz_keeps_unknowns_without_strong_neighbours():
    """Unknowns no aggregate holds (a diagonal block: fem-th's pressure complement at
    k = 0) are subdomains of their own, and a diagonal matrix alone is solved exactly."""
    import pyamg

    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(20, 20))
    diagonal = sp.diags(np.linspace(1.0, 2.0, 50))
    for M in (sp.csr_matrix(sp.block_diag([sp.kronsum(one, one), diagonal])),
              sp.csr_matrix(diagonal)):
        ml = pyamg.smoothed_aggregation_solver(M, max_coarse=10, keep=True)
        sub, _ = subdomains(ml.levels[0].C, ml.levels[0].AggOp, 1)
        assert set(sub) == set(range(M.shape[0]))
    b = np.arange(50.0)
    assert np.allclose(amg(M, "schwarz", 0.0)(b), b / diagonal.diagonal(), rtol=1e-12)


def test_efg_corrections_take_few_iterations():
    """The undrained bench step (stabilised Nitsche EFG, Cam-clay, 10^3 nodes) takes at
    most 20 FGMRES iterations per Newton residual (49 in 4 measured). With pyamg's
    default Gauss-Seidel smoother and the lumped pressure mass a correction took about
    200 (837 FGMRES iterations in 5 residuals at 10^4 nodes)."""
    with linear_solver("krylov"):
        result = soilwater.efg.solver.solve(compression(1000, "cam-clay", krylov=True),
                                            progress=False)
    s = result.summary
    assert 0 < s["linear_iterations"] <= 20 * s["newton_iterations"]


def test_the_forcing_cap_keeps_inexact_newton_on_exact_newtons_path(monkeypatch):
    """On the undrained bench step (stabilised Nitsche EFG, Cam-clay, 3 x 10^3 nodes)
    the first correction, solved to EFG's forcing cap (``soilwater.efg.system.FORCING``), lands
    where the exact one does (scaled residual within 1 %; measured 0.1 %), and inexact
    Newton through FGMRES then takes as many residuals as full Newton with exact solves
    (4; its last two are 50 and 20 times from the tolerance). Capped at 1e-4 instead,
    the first iterate is 30 % further off (and Newton needs one residual more)."""
    def residuals(solver, setting=()):
        seen, residual = [], soilwater.nonlinear.newton._residual

        def traced(system, dx):
            R, scaled = residual(system, dx)
            seen.append(scaled)
            return R, scaled

        with monkeypatch.context() as m, linear_solver(solver):
            m.setattr(soilwater.nonlinear.newton, "_residual", traced)
            for module, name, value in setting:
                m.setattr(module, name, value)
            soilwater.efg.solver.solve(compression(3000, "cam-clay", krylov=True), progress=False)
        return seen

    exact = residuals("superlu", setting=[(soilwater.nonlinear.newton, "must_refactorise",
                                           lambda *args: True)])
    inexact = residuals("krylov")
    loose = residuals("krylov", setting=[(soilwater.efg.system, "FORCING", 1e-4)])
    assert len(inexact) == len(exact)
    assert inexact[1] == pytest.approx(exact[1], rel=0.01)
    assert loose[1] > 1.2 * exact[1]


@pytest.mark.parametrize("field, value", [("smoother", "jacobi"), ("strength", 1.0),
                                          ("strength", -0.01), ("forcing", 0.0),
                                          ("forcing", 1.0)])
def test_layout_rejects_unknown_smoothers_and_thresholds(field, value):
    with pytest.raises(ValueError, match=f"Layout.{field}="):
        Layout(**{field: value})


def test_krylov_needs_a_described_system(monkeypatch):
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "krylov")
    K, _ = biot()
    with pytest.raises(InputError, match="krylov needs"):
        factorise(K, Layout(groups=np.zeros(K.shape[0], int)))


def runs(case, method):
    """The run of ``method`` with SuperLU and with the Krylov back-end."""
    def solve():
        if method == "efg":
            return soilwater.efg.solver.solve(case, progress=False)
        return soilwater.fem.solver.solve(case, method, progress=False)

    with linear_solver("superlu"):
        direct = solve()
    with linear_solver("krylov"):
        krylov = solve()
    return direct, krylov


@pytest.mark.parametrize("name, method, overrides", [
    ("unconfined-compression", "efg", ["efg.essential=\"nitsche\"", "time.end=1.2",
                                       "time.steps=6"]),
    ("unconfined-compression", "fem-p1p1-stab", ["time.end=1.2", "time.steps=6"]),
    ("terzaghi", "efg", ["efg.essential=\"nitsche\"", "time.end=0.01"]),
    ("mandel", "fem-th", ["time.end=0.01"]),
    ("mandel", "efg", ["efg.essential=\"nitsche\"", "time.end=0.01"]),
])
def test_runs_agree_with_the_direct_solver(name, method, overrides):
    """Inexact Newton through FGMRES converges to the same steps: p, q and the
    settlement agree to 1e-6 of their range (the Newton tolerance is 1e-8 of the
    scales); the Krylov iterations are counted per step; each step (none is cut back
    here) builds one preconditioner and keeps it for every Newton iteration."""
    case = load_case(name, overrides)
    direct, krylov = runs(case, method)
    s = krylov.summary
    assert s["linear_solver"].startswith("krylov pyamg")
    assert s["linear_iterations"] == krylov.history.linear_iterations.sum() > 0
    assert s["cutbacks"] == 0 and s["factorisations"] == len(krylov.history)
    for column in ("p", "q", "settlement"):
        a, b = direct.history[column], krylov.history[column]
        assert np.abs(a - b).max() <= 1e-6 * max(np.abs(a).max(), 1e-12), column


@pytest.mark.parametrize("method, overrides, iterative", [
    ("efg", ['efg.essential="nitsche"', 'efg.stabilisation="perturbation"'], True),
    ("efg", ['efg.essential="penalty"'], False),
    ("efg", ['efg.stabilisation="none"'], False),
    ("fem-p1p1-stab", [], True),
    ("fem-p1p1", [], False),
])
def test_krylov_is_the_default_on_large_systems_that_suit_it(monkeypatch, method,
                                                            overrides, iterative):
    """With no SOILWATER_LINEAR_SOLVER, a run of at least KRYLOV_FROM unknowns (lowered
    here) is solved by the Krylov back-end when its discretisation suits it, and the
    result names the back-end that solved it; below KRYLOV_FROM, the direct one."""
    monkeypatch.delenv("SOILWATER_LINEAR_SOLVER", raising=False)
    direct = backend()
    case = load_case("unconfined-compression", ["discretisation.nx=5", "discretisation.ny=7",
                                                "time.end=0.2", "time.steps=1", *overrides])

    def solver_of_a_run():
        result = (soilwater.efg.solver.solve(case, progress=False) if method == "efg"
                  else soilwater.fem.solver.solve(case, method, progress=False))
        return result.summary["linear_solver"].split()[0]

    monkeypatch.setattr(soilwater.linalg.backends, "KRYLOV_FROM", 50)
    assert solver_of_a_run() == ("krylov" if iterative else direct)
    monkeypatch.setattr(soilwater.linalg.backends, "KRYLOV_FROM", 10**6)
    assert solver_of_a_run() == direct


def test_backend_switches_at_krylov_from_and_the_environment_overrides_it(monkeypatch):
    monkeypatch.delenv("SOILWATER_LINEAR_SOLVER", raising=False)
    direct, size = backend(), soilwater.linalg.backends.KRYLOV_FROM
    assert direct != "krylov"
    assert backend(size - 1, iterative=True) == direct
    assert backend(size, iterative=True) == "krylov"
    assert backend(size, iterative=False) == direct
    monkeypatch.setenv("SOILWATER_LINEAR_SOLVER", "superlu")
    assert backend(size, iterative=True) == "superlu"
