"""The experiment scripts of ``docs/experiments/`` run at their smallest sizes.

Each script's ``main(argv)`` runs in this process on a bench case of about a hundred
nodes (a few hundred where the AMG needs two levels), whole runs cut to two steps, and
what it returns is checked: every row it promises, finite and positive times, whole
iteration counts, and what the study pages state of the numbers (agreements, exact
solves). PARDISO-only experiments are skipped without pypardiso; the others run on
SuperLU and the Krylov back-end. ``common.solve``, which the experiments use to pass a
layout or watch a run, is checked against the solvers' own run.
"""

import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from soilwater.case.loader import load_case
from soilwater.linalg.backends import linear_solver

EXPERIMENTS = Path(__file__).resolve().parents[1] / "docs" / "experiments"
#: Whole runs cut to two steps of 0.2 s.
SHORT = ["--set", "time.end=0.4", "--set", "time.steps=2"]
#: The post-peak case on the built-in 7 x 9 grid.
SMALL_GRID = ["--set", "discretisation.nx=7", "--set", "discretisation.ny=9", *SHORT]


def script(name):
    """The experiment module ``name``, imported as ``python docs/experiments/name.py``
    would (the scripts import ``common`` from their folder)."""
    sys.path.insert(0, str(EXPERIMENTS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(EXPERIMENTS))


def positive(value):
    return math.isfinite(value) and value > 0


def counts(value):
    return float(value) == int(value) and value >= 1


def test_solve_with_nothing_changed_is_the_solvers_run():
    common = script("common")
    for method in ("efg", "fem-p1p1-stab"):
        case = load_case("unconfined-compression", "time.end=0.4", "time.steps=2")
        with linear_solver("superlu"):
            own = common.solve(case, method)
            composed = common.solve(case, method, layout=lambda layout: layout)
        for column in ("p", "q", "settlement"):     # the same run, up to round-off
            np.testing.assert_allclose(own.history[column], composed.history[column],
                                       rtol=1e-10)
        np.testing.assert_array_equal(own.history.iterations, composed.history.iterations)


def test_krylov_steps():
    rows = script("krylov_steps").main(["100", "--solvers", "superlu", "krylov"])
    assert [row["solver"] for row in rows] == ["superlu", "krylov"]
    for row in rows:
        assert row["status"] == "ok"
        assert positive(row["step"]) and positive(row["peak_mb"]) and counts(row["iterations"])
    assert counts(rows[1]["linear_iterations"])


def test_krylov_runs_agree_with_the_direct_solver():
    rows = script("krylov_runs").main(["--run", "unconfined-compression:efg:nitsche",
                                       "--solvers", "superlu", "krylov", *SHORT])
    assert [row["variant"] for row in rows] == ["superlu", "krylov", "agreement"]
    assert all(row["failed"] is None and counts(row["newton"]) for row in rows[:2])
    assert counts(rows[1]["fgmres"])
    assert all(rows[2][c] < 1e-6 for c in ("p", "q", "settlement"))


def test_krylov_newton():
    rows = script("krylov_newton").main(["--nodes", "100", "--forcings", "1e-5",
                                         "--direct", "superlu"])
    forcing, modified, full = rows
    for row in rows:
        assert row["failed"] is None and row["residuals"][-1] < 1e-8
    assert counts(forcing["fgmres"]) and full["fgmres"] == 0
    assert full["tangents"] == len(full["residuals"]) - 1       # one per correction
    assert modified["tangents"] < len(modified["residuals"]) - 1


def test_krylov_unstabilised():
    rows = script("krylov_unstabilised").main(["--nodes", "100"])
    assert [row["stabilisation"] for row in rows] == ["none", "perturbation"]
    assert all(row["failed"] is None and counts(row["fgmres"]) for row in rows)


def test_memory():
    rows = script("memory").main(["--nodes", "100"])
    assert len(rows) == 4
    peaks = [row["peak_mb"] for row in rows]
    assert all(positive(row["resident_mb"]) for row in rows) and peaks == sorted(peaks)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="prctl and /proc: Linux")
def test_faults():
    rows = script("faults").main(["100"])
    assert [row["huge_pages"] for row in rows] == [True, False]
    for row in rows:
        assert row["status"] == row["build_status"] == "ok"
        assert positive(row["step"]) and counts(row["faults"]) and counts(row["build_faults"])


def test_krylov_smoother():
    rows = script("krylov_smoother").main(["100", "--methods", "fem-p1p1-stab",
                                           "--whole", "fem-th", *SHORT])
    steps, whole = rows[:2], rows[2:]
    assert [row["smoother"] for row in rows] == ["gauss_seidel", "schwarz"] * 2
    assert all(row["status"] == "ok" and counts(row["linear_iterations"]) for row in steps)
    assert all(row["failed"] is None and counts(row["fgmres"]) for row in whole)


def test_krylov_strength():
    rows = script("krylov_strength").main(["0.01", "--sizes", "100",
                                           "--whole", "fem-p1p1-stab", *SHORT])
    step, whole = rows
    assert step["status"] == "ok" and positive(step["peak_mb"])
    assert counts(step["linear_iterations"])
    assert whole["failed"] is None and counts(whole["fgmres"])


def test_krylov_overlap_keeps_more_inverses_the_more_subdomains_grow():
    wide, none = script("krylov_overlap").main(["--nodes", "600", "--overlaps", "0.25",
                                                "1.01"])
    assert wide["inverses_mb"] > none["inverses_mb"] > 0
    assert counts(wide["iterations"]) and positive(wide["build"])


def test_threads_give_the_same_step():
    rows = script("threads").main(["100", "--threads", "1", "2"])
    assert all(row["status"] == "ok" for row in rows)
    one, two = rows
    assert one["iterations"] == two["iterations"] >= 1
    assert one["linear_iterations"] == two["linear_iterations"]


def test_schur_exact_blocks_take_two_iterations():
    rows = script("schur").main(["100"])
    assert len(rows) == 3 * 6 and all(counts(row["iterations"]) for row in rows)
    exact = [row for row in rows if row["displacement"] == "exact"
             and row["pressure"] == "true Schur, exact"]
    assert len(exact) == 1 and exact[0]["iterations"] <= 3


def test_spectral():
    rows = script("spectral").main(["100", "--tolerance", "1e-9", "--runs", "2"])
    assert {row["restart"] for row in rows} == {"complex", "real"}
    assert all(positive(row["rho"]) and row["error"] >= 0 for row in rows)
    assert all(row["vector"] == "float64" for row in rows if row["restart"] == "real")


def test_direct_orderings():
    rows = script("direct_orderings").main(["100", "--methods", "efg", "fem-p1p1-stab"])
    assert len(rows) == 4
    assert all(row["entries"] >= row["unknowns"] and row["seconds"] >= 0 for row in rows)


def test_direct_symmetric():
    pytest.importorskip("pypardiso")
    rows = script("direct_symmetric").main(["100", "--tolerances", "1e-8"])
    penalty, nitsche = rows
    assert penalty["asymmetry"] < 1e-6 < 1e-3 < nitsche["asymmetry"]
    assert all(counts(row["iterations"]) and row["difference"] < 1e-6 for row in rows)


def test_direct_single():
    pytest.importorskip("pypardiso")
    rows = script("direct_single").main(["100", "--methods", "fem-p1p1-stab", "--run",
                                         "unconfined-compression:fem-p1p1-stab", *SHORT])
    double, single = rows[:2]
    assert double["precision"] == "double" and double["residuals"][-1] < 1e-12
    assert single["precision"] == "single" and single["residuals"][-1] <= 1e-12
    steps = {row["precision"]: row for row in rows[2:4]}
    assert steps["double"]["single_factorisations"] == 0
    assert steps["single"]["single_factorisations"] == steps["single"]["factorisations"] >= 1
    assert rows[-1]["variant"] == "agreement"
    assert all(rows[-1][c] < 1e-6 for c in ("p", "q", "settlement"))


def test_post_peak_branches_keep_the_homogeneous_solution_early():
    rows = script("post_peak_branches").main([
        "--path", "efg:superlu:modified", "--path", "efg:superlu:full",
        "--path", "efg:krylov:newton", "--every", "0.2", *SMALL_GRID])
    for row in rows:
        assert row["failed"] is None and counts(row["newton"])
        assert [t for t, _, _ in row["spreads"]] == pytest.approx([0.2, 0.4])
        assert all(q < 1e-8 and p < 1e-8 for _, q, p in row["spreads"])


def test_post_peak_tangent_matches_central_differences():
    rows = script("post_peak_tangent").main(["--times", "0.4", "--steps", "1e-4",
                                             "--solver", "superlu", *SMALL_GRID])
    assert [row["iterate"] for row in rows] == [0, 1, 2]
    for row in rows[1:]:
        u, _ = row["differences"]["Newton"][1e-4]
        assert u < 1e-6
        assert row["preconditioners"]["of"] == 2 * 63


@pytest.mark.filterwarnings("ignore:invalid value encountered in log2")   # t = 3T: settled
def test_gibson():
    out = script("gibson").main(["--cells", "100", "--per-decade", "10",
                                 "--coarsest", "25", "3", "--levels", "3"])
    assert len(out["closed_forms"]) == 4
    assert all(row["settlement"] < 1e-2 and row["pressure"] < 1e-2
               for row in out["closed_forms"])
    assert out["convergence"]["settlement"].shape == (3, 5)
    small = out["small_strain"]
    assert 0 < small["final"] < small["small_final"]


def test_integration_schemes_steps():
    table = script("integration").main(["--steps", "--core", "2", "--counts", "25", "50",
                                        "--schemes", "gauss", "paper"])["steps"]
    assert set(table) == {"gauss", "paper"}
    assert all(1.0 < p < 1.2 for p in table["gauss"]), table     # over Prandtl's, 0.1 B
    script("integration").main(["--consistency", "--drift", "--core", "2", "--counts", "25",
                                "--first", "1", "--schemes", "nodal"])


def test_schemes():
    rows = script("schemes").main(["--cases", "unconfined-compression", "inf-sup",
                                   "--schemes", "paper", "nodal", "--essential", "penalty",
                                   "--stabilisation", "none", "--sizes", "5", "9", *SHORT])
    runs = [row for row in rows if row["case"] == "unconfined-compression"]
    assert [row["integration"] for row in runs] == ["paper", "nodal"]
    for row in runs:
        assert row["completed"] and counts(row["newton"]) and positive(row["run_time"])
        assert 0 <= row["path_error"] < 0.1 and 0 <= row["err_max"] < 0.01   # 2 steps
    tests = [row for row in rows if row["case"] == "inf-sup"]
    assert [(row["method"], row["n"]) for row in tests[::2]] == [
        ("efg paper", 5), ("efg paper", 9), ("efg nodal", 5), ("efg nodal", 9)]
    assert all(positive(row["beta"]) for row in tests), tests


def test_locking_runs_every_table():
    out = script("locking").main([
        "--steps", "2", "--core", "2", "--cores", "2", "--fem-cores", "2",
        "--variant-cores", "2", "--fine-core", "2", "--factors", "4", "--pairs", "1.6,1.6",
        "--fine-runs", "nodal,efg.scale_u=2.0"])
    assert {t: len(rows) for t, rows in out.items()} == {
        "sizes": 3 + 2, "variants": 4 * (2 + 2), "stabilisations": 3 + 2, "supports": 2,
        "fine": 1}
    rows = [row for table in out.values() for row in table]
    for row in rows:
        assert row["reached"] and row["failed"] is None, row
        assert row["nodes"] == row["p"] == 100 and counts(row["u"]), row
        assert positive(row["seconds"]) and positive(row["pressure"]), row
        assert row["pw_min"] <= row["pw_max"], row
        assert math.isfinite(row["wiggle"]) and row["wiggle"] >= 0, row
    for row in out["variants"]:
        assert positive(row["ratio"]), row
        if row["variant"] in ("drained", "elastic-drained"):   # dissipated within a step
            assert max(-row["pw_min"], row["pw_max"]) < 1e-3, row
    assert [row["ratio"] for row in out["variants"] if row["method"] == "fem-th"] == [1.0] * 4


def test_bad_input_is_one_line(capsys):
    with pytest.raises(SystemExit) as stopped:
        script("krylov_runs").main(["--set", "time.steps=-1"])
    assert stopped.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_coarse_pressure_reduces_the_pressure_unknowns_and_restores_the_solver():
    locking = script("locking")
    out = script("coarse_pressure").main(["--core", "2", "--steps", "2",
                                          "--spacings", "1", "2"])
    assert len(out) == (1 + 2 * 2) + 3 * (1 + 2)
    for row in out:
        assert row["reached"] and row["failed"] is None, row
        assert positive(row["pressure"]), row
    efg = [row for row in out if "fem-th" not in row["method"]]
    assert {row["p"] for row in efg if row["s"] == 1} == {100}
    assert all(25 <= row["p"] < 50 for row in efg if row["s"] == 2), efg
    own = locking.run(2, 2, "efg", "gauss")          # the package's solver, unpatched
    first = next(row for row in efg if row["variant"] == "undrained penalty")
    assert first["pressure"] == pytest.approx(own["pressure"], rel=1e-6)


def test_footing_edge_fits_force_against_width_for_both_methods():
    out = script("footing_edge").main(["--cores", "2", "--widths", "1", "2", "--steps", "2"])
    runs = [row for row in out if "force" in row]
    assert [(r["method"], r["a"]) for r in runs] == [
        ("fem-th", 0.5), ("fem-th", 1.0), ("efg", 0.5), ("efg", 1.0)]
    for method in ("fem-th", "efg"):
        narrow, wide = (r["force"] for r in runs if r["method"] == method)
        assert 0 < narrow < wide, runs                 # a wider footing carries more
    (fit,) = [row for row in out if "fits" in row]
    assert positive(fit["radius"]) and fit["h"] == 0.5
    for slope, delta in fit["fits"].values():
        assert positive(slope) and math.isfinite(delta)
