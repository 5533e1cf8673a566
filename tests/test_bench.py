"""``make bench`` machinery on tiny inputs: children that die or hang, the plan of runs,
the targets' verdicts and the growth fits (no timing is asserted)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilwater.linalg.backends import available
from soilwater.studies.bench import analysis, plan, report, runs, study
from soilwater.studies.harness import machine

ROOT = Path(__file__).parents[1]


def _killed():
    os.kill(os.getpid(), signal.SIGKILL)


def _raises():
    raise RuntimeError("no convergence\nsecond line")


def test_in_child_returns_the_value():
    assert runs.in_child(divmod, 7, 2, timeout=30) == ((3, 1), "ok")


@pytest.mark.parametrize("fn,args,status", [
    (os._exit, (3,), "died (exit 3)"),
    (_killed, (), f"died (signal {int(signal.SIGKILL)})"),
    (_raises, (), "failed: RuntimeError: no convergence"),
])
def test_in_child_reports_a_child_that_gives_no_answer_at_once(fn, args, status):
    tic = time.perf_counter()
    assert runs.in_child(fn, *args, timeout=60) == (None, status)
    assert time.perf_counter() - tic < 20       # not the whole timeout


def test_in_child_stops_a_child_that_hangs():
    tic = time.perf_counter()
    value, status = runs.in_child(time.sleep, 60, timeout=0.5)
    assert status == "stopped at 0.5 s"
    assert 1 < value["peak_mb"] < 1e4                # this process's memory, in MB
    assert time.perf_counter() - tic < 20


@pytest.mark.parametrize("sizes", ["1000,abc", "1000,", "1e3,2.5e3,0.5", "50", "nan", "1e400"])
def test_bad_sizes_are_one_line_and_write_nothing(tmp_path, sizes):
    proc = subprocess.run([sys.executable, "-m", "soilwater.cli", "bench", "--sizes", sizes,
                           "--out", str(tmp_path / "bench.md")], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error: --sizes"), proc.stderr
    assert not list(tmp_path.iterdir())


def test_sizes_accept_exponents():
    assert plan.parse_sizes("1000,3e5, 1e6") == [1000, 300_000, 1_000_000]


def test_numpy_blas_names_the_openblas_variables_it_was_loaded_with():
    env = {**os.environ, "OPENBLAS_CORETYPE": "Prescott"}
    env.pop("OPENBLAS_L2_SIZE", None)
    code = "from soilwater.studies.harness import machine; print(machine.numpy_blas())"
    line = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True,
                          capture_output=True, text=True, timeout=120).stdout
    assert "OPENBLAS_CORETYPE Prescott, OPENBLAS_L2_SIZE unset" in line
    if "core " in line and "core unknown" not in line:      # OpenBLAS says which kernel
        assert "Haswell" not in line and "Zen" not in line and "SkylakeX" not in line


def test_dgemm_rates_are_positive_and_mkl_is_measured_where_pardiso_is():
    rates = machine.dgemm(300, repeat=1)
    assert rates["n"] == 300 and rates["numpy_gflops"] > 0
    assert (rates["mkl_gflops"] > 0) == available("pardiso")


def test_make_bench_unsets_the_openblas_variables_before_numpy_loads():
    recipe = (ROOT / "Makefile").read_text().split("\nbench:")[1].split("\n\n")[0]
    line = next(line for line in recipe.splitlines() if "soilwater bench" in line)
    assert all(f"-u {name}" in line.split("soilwater")[0]
               for name in machine.OPENBLAS_VARIABLES)


def test_plan_runs_only_efg_and_fem_p1p1_stab_on_cam_clay_from_large_from():
    runs = plan.plan([1_000, plan.LARGE_FROM, 1_000_000])
    small = [run for run in runs if run.nodes == 1_000]
    assert len(small) == (len(plan.METHODS) - 1 + len(plan.SCHEMES)) * len(plan.MATERIALS)
    assert {run.solver for run in small} == {plan.direct()}
    assert {run.limit for run in small} == {plan.TIME_LIMIT}
    large = [run for run in runs if run.nodes >= plan.LARGE_FROM]
    assert [run[:4] for run in large] == [
        (n, "cam-clay", m, s) for n in (plan.LARGE_FROM, 1_000_000)
        for m, s in [*(("efg", s) for s in plan.SCHEMES), ("fem-p1p1-stab", "-")]]
    assert {run.solver for run in large} == {"krylov"}
    assert {run.limit for run in large} == {plan.LARGE_TIME_LIMIT}


def test_plan_runs_every_efg_run_once_per_scheme_and_fem_once():
    runs = plan.plan([1_000, plan.BOTH_FROM, plan.KRYLOV_FROM])
    efg = [run for run in runs if run.method == "efg"]
    by_scheme = {scheme: [(r.nodes, r.material, r.solver, r.ready) for r in efg
                          if r.integration == scheme] for scheme in plan.SCHEMES}
    assert len(by_scheme["paper"]) > 0
    assert all(runs_ == by_scheme["paper"] for runs_ in by_scheme.values())
    assert {run.integration for run in runs if run.method != "efg"} == {"-"}
    assert plan.plan([1_000], ("fem-th",)) == plan.plan([1_000], ("fem-th",), schemes=())


def test_plan_skips_nodal_on_krylov_from_large_from_with_its_reason():
    runs = plan.plan([plan.BOTH_FROM, plan.LARGE_FROM], ("efg",), ("cam-clay",))
    skipped = [run for run in runs if run.skip]
    assert [(run.nodes, run.integration, run.solver) for run in skipped] == [
        (plan.LARGE_FROM, "nodal", "krylov")]
    assert "krylov" in skipped[0].skip.lower() or "FGMRES" in skipped[0].skip


def test_compression_sets_the_scheme_and_every_efg_setting_it_depends_on():
    for scheme in plan.SCHEMES:
        for krylov, conditions in ((False, ("penalty", "none")),
                                   (True, ("nitsche", "perturbation"))):
            efg = plan.compression(200, krylov=krylov, integration=scheme).efg
            assert (efg.integration, efg.essential, efg.stabilisation) == (scheme,
                                                                          *conditions)


def test_plan_runs_the_large_methods_on_both_solvers_from_both_from():
    runs = plan.plan([plan.BOTH_FROM], schemes=("paper",))
    krylov = [run[:3] for run in runs if run.solver == "krylov"]
    assert krylov == [(plan.BOTH_FROM, material, m) for material in plan.MATERIALS
                      for m in plan.LARGE_METHODS]
    ready = [run[:3] for run in runs if run.solver != "krylov" and run.ready]
    assert ready == ([(plan.BOTH_FROM, material, "efg") for material in plan.MATERIALS]
                     if plan.direct() == "pardiso" else [])   # single precision there
    assert len(runs) == len(plan.METHODS) * len(plan.MATERIALS) + len(krylov) + len(ready)
    assert all(run.ready for run in runs if run.solver == "krylov")
    assert not any(run.solver == "krylov" or run.ready
                   for run in plan.plan([plan.BOTH_FROM - 1]))


def test_solver_and_limit_change_at_their_sizes(monkeypatch):
    assert plan.solver_for(plan.KRYLOV_FROM - 1) in ("pardiso", "superlu")
    assert plan.solver_for(plan.KRYLOV_FROM) == "krylov"
    assert plan.time_limit(100_000) == plan.TIME_LIMIT
    assert plan.time_limit(plan.LARGE_FROM) == plan.LARGE_TIME_LIMIT
    monkeypatch.setattr(plan, "KRYLOV_FROM", 500)
    assert plan.solver_for(500) == "krylov"


def test_steps_records_the_solver_per_row_and_an_unavailable_back_end(monkeypatch):
    """Tiny sizes only: the iterative back-end is asked for from 300 nodes here."""
    monkeypatch.setattr(plan, "KRYLOV_FROM", 300)
    lines = []
    table = runs.steps([200, 300], methods=("efg",), materials=("elastic",),
                        progress=lines.append, schemes=("paper",))
    assert list(table.columns) == list(runs.COLUMNS) and len(lines) == 2
    small, large = table.iloc[0], table.iloc[1]
    assert small.status == "ok" and small.solver == plan.direct()
    assert small.iterations >= 1 and small.step > 0 and small.limit_s == plan.TIME_LIMIT
    assert small.kb_per_node == pytest.approx(small.peak_mb * 1e3 / small.nodes)
    if small.factor_flops == small.factor_flops:             # the back-end counts them
        assert small.factor_gflops_lb == pytest.approx(small.factor_flops / small.solve / 1e9)
    assert large.solver == "krylov"
    if not plan.usable("krylov"):
        assert large.status == "krylov not available" and large.step != large.step
        assert "krylov not available" in lines[1]


def test_steps_runs_each_scheme_and_reads_its_points_and_tangent_entries(monkeypatch):
    """A tiny run of each scheme beside fem-p1p1-stab; a skipped run is a row with its
    reason and runs nothing."""
    monkeypatch.setattr(plan, "SKIPS", {("efg", "nodal", plan.direct()): (300, "a reason")})
    lines = []
    table = runs.steps([200, 300], methods=("efg", "fem-p1p1-stab"), materials=("elastic",),
                       progress=lines.append)
    small = table[table.nodes < 250].set_index("integration")
    assert list(small.index) == [*plan.SCHEMES, "-"] and (small.status == "ok").all()
    assert (small.step > 0).all() and (small.assembly > 0).all()
    assert small.loc["nodal", "points_per_node"] == 1.0       # the nodes themselves
    # three Gauss points per triangle of the same initial Delaunay triangulation
    assert small.loc["gauss", "points_per_node"] == small.loc["paper", "points_per_node"]
    assert 4.0 < small.loc["paper", "points_per_node"] < 6.0
    assert (small.entries_per_row > 9).all()                 # more than one node per row
    assert (small.loc[list(plan.SCHEMES), "entries_per_row"]
            > small.loc["-", "entries_per_row"]).all()       # MLS supports reach further
    nodal = table[(table.nodes > 250) & (table.integration == "nodal")].iloc[0]
    assert nodal.status == "skipped: a reason" and nodal.step != nodal.step
    assert nodal.points_per_node != nodal.points_per_node    # not counted either
    assert any("skipped: a reason" in line for line in lines)
    against = analysis.schemes(table)
    assert list(against.integration[against.nodes < 250]) == list(plan.SCHEMES)
    assert against.fem_points_per_node.notna().all()
    first = against.iloc[0]
    assert first.step == pytest.approx(small.loc["paper", "step"] / small.loc["-", "step"])


def test_counts_are_those_of_the_tangent_the_solver_builds():
    """The EFG tangent stores the node pattern once per pair of its three fields."""
    from soilwater.efg import solver
    from soilwater.efg.discretisation import discretise
    from soilwater.nonlinear.history import TIMERS

    counted = runs.counts("efg", 200, "gauss")
    case = plan.compression(200, integration="gauss")
    model = solver.Model.build(case)
    points = solver._initial_points(model)
    disc = discretise(model, points.nodes, points.nodes, dict.fromkeys(TIMERS, 0.0),
                      points.cells)
    n = len(points.nodes)
    assert counted["points_per_node"] == len(disc.w) / n
    assert not model.scales.pin_pressure and not disc.bc.rigid.any()   # no border: 3n rows
    assert counted["entries_per_row"] == pytest.approx(9 * disc.patterns["domain"].nnz
                                                       / (3 * n))


def _rows(*rows):
    """A table of :func:`runs.steps` from (method, nodes, step, status, solver, peak_mb),
    EFG with the paper's scheme."""
    return pd.DataFrame([
        {"method": method, "integration": "paper" if method == "efg" else "-",
         "material": "cam-clay", "nodes": nodes, "solver": solver,
         "efg": "-" if method != "efg" else {"krylov": "nitsche, perturbation"}.get(
             solver, "penalty, none"),
         "status": status, "step": step if status == "ok" else np.nan,
         "peak_mb": peak if status == "ok" else np.nan,
         "limit_s": plan.time_limit(nodes)}
        for method, nodes, step, status, solver, peak in rows]).reindex(
            columns=list(runs.COLUMNS))


def test_scale_targets_measured_where_every_run_completed():
    sizes = (10_296, 100_010, 1_004_276)
    efg = [("efg", n, n * 1e-4, "ok", "krylov" if n > 3e5 else "pardiso", 2000.0)
           for n in sizes]
    stab = [("fem-p1p1-stab", n, n * 1e-4 / r, "ok", "krylov" if n > 3e5 else "pardiso", 1.0)
            for n, r in zip(sizes, (1.5, 3.0, 2.0))]
    goals = analysis.scale_targets(_rows(*efg, *stab), "a CPU")
    met = dict(zip(goals.target, goals.met))
    assert met["EFG Cam-clay step at 1e5 nodes [s]"] == "yes"          # 10.0 s <= 16.05
    assert met["EFG Cam-clay peak memory at 1e5 nodes [GB]"] == "yes"  # 2.0 GB
    assert met["EFG Cam-clay step at 1e6 nodes [s]"] == "yes"
    growth = goals[goals.target.str.contains("growth")].iloc[0]
    assert growth.measured == pytest.approx(1.0) and growth.met == "yes"
    assert "pardiso, krylov" in growth["where"]
    ratios = goals[goals.target.str.contains("fem-p1p1-stab")]
    assert ratios.measured.tolist() == pytest.approx([1.5, 3.0, 2.0])
    assert ratios.met.tolist() == ["yes", "**no**", "yes"]
    assert "the CPU may differ" in goals["where"].iloc[0] and "a CPU" in goals["where"].iloc[0]


def test_scale_targets_never_say_yes_for_a_run_that_did_not_complete():
    table = _rows(("efg", 10_296, 1.0, "ok", "pardiso", 500.0),
                  ("efg", 100_010, 0, "stopped at 240 s", "pardiso", 0),
                  ("efg", 1_004_276, 0, "died (signal 9)", "krylov", 0),
                  ("fem-p1p1-stab", 10_296, 0, "stopped at 240 s", "pardiso", 0),
                  ("fem-p1p1-stab", 100_010, 5.0, "ok", "pardiso", 0),
                  ("fem-p1p1-stab", 1_004_276, 0, "krylov not available", "krylov", 0))
    goals = analysis.scale_targets(table)
    assert (goals.met == "not measured").all(), goals
    assert goals.measured.isna().all()
    where = dict(zip(goals.target + goals["where"].str.split(",").str[0], goals["where"]))
    assert "stopped at 240 s" in where["EFG Cam-clay step at 1e5 nodes [s]100010 nodes"]
    assert "died (signal 9)" in where["EFG Cam-clay step at 1e6 nodes [s]1004276 nodes"]
    ratios = goals[goals.target.str.contains("fem-p1p1-stab")]["where"].tolist()
    assert "ratio < 0.00417" in ratios[0]                 # 1 s against more than 240 s
    assert "ratio > 48" in ratios[1]                      # more than 240 s against 5 s
    assert "krylov not available" in ratios[2]
    assert "only" in goals[goals.target.str.contains("growth")]["where"].iloc[0] or \
        "fewer than two" in goals[goals.target.str.contains("growth")]["where"].iloc[0]


def test_scale_growth_needs_both_ends_and_a_missing_size_is_not_measured():
    table = _rows(("efg", 10_296, 1.0, "ok", "pardiso", 500.0),
                  ("efg", 100_010, 10.0, "ok", "pardiso", 500.0),
                  ("efg", 300_675, 30.0, "ok", "krylov", 500.0))
    goals = analysis.scale_targets(table).set_index("target")
    growth = goals.loc["EFG Cam-clay step growth exponent, 1e4 to 1e6 nodes "
                       "(paper: faster solver at each size)"]
    assert growth.met == "not measured" and "only (fit 1.0" in growth["where"]
    assert goals.loc["EFG Cam-clay step at 1e6 nodes [s]"]["where"] == "no run at 1e6 nodes"
    assert goals.loc["EFG Cam-clay step at 1e6 nodes [s]"].met == "not measured"


def test_scale_targets_take_each_method_on_its_faster_solver():
    """Both solvers at 1e4 and 1e5: the 1e5 step and memory per solver, the growth on the
    faster one at each size and per solver, the ratio of each method's faster step."""
    table = _rows(("efg", 10_296, 1.0, "ok", "pardiso", 500.0),
                  ("efg", 10_296, 2.0, "ok", "krylov", 400.0),
                  ("efg", 100_010, 40.0, "ok", "pardiso", 6000.0),
                  ("efg", 100_010, 20.0, "ok", "krylov", 2500.0),
                  ("efg", 1_004_276, 200.0, "ok", "krylov", 20000.0),
                  ("fem-p1p1-stab", 10_296, 0.5, "ok", "pardiso", 0),
                  ("fem-p1p1-stab", 10_296, 0.8, "ok", "krylov", 0),
                  ("fem-p1p1-stab", 100_010, 30.0, "stopped at 240 s", "pardiso", 0),
                  ("fem-p1p1-stab", 100_010, 8.0, "ok", "krylov", 0))
    goals = analysis.scale_targets(table)
    step = goals[goals.target == "EFG Cam-clay step at 1e5 nodes [s]"]
    assert step.measured.tolist() == [40.0, 20.0]
    assert [w.split(",")[1].split(";")[0].strip() for w in step["where"]] == [
        "pardiso", "krylov"]
    memory = goals[goals.target == "EFG Cam-clay peak memory at 1e5 nodes [GB]"]
    assert memory.met.tolist() == ["**no**", "yes"]
    growth = goals[goals.target.str.contains("growth")].set_index("target").measured
    name = "EFG Cam-clay step growth exponent, 1e4 to 1e6 nodes (paper: {})"
    assert growth[name.format("faster solver at each size")] == pytest.approx(
        analysis.exponent([10_296, 100_010, 1_004_276], [1.0, 20.0, 200.0]))
    assert growth[name.format("krylov; nitsche, perturbation")] == pytest.approx(
        analysis.exponent([10_296, 100_010, 1_004_276], [2.0, 20.0, 200.0]))
    assert np.isnan(growth[name.format("pardiso; penalty, none")])
    ratios = goals[goals.target.str.contains("fem-p1p1-stab")]
    assert ratios.measured.tolist() == pytest.approx([2.0, 2.5])      # 1/0.5, 20/8
    assert "efg paper krylov (nitsche, perturbation), fem-p1p1-stab krylov" in \
        ratios["where"].iloc[1]


def test_scale_targets_judge_each_scheme_on_its_own_runs():
    table = _rows(("efg", 10_296, 1.0, "ok", "pardiso", 500.0),
                  ("efg", 10_296, 3.0, "ok", "pardiso", 500.0),
                  ("fem-p1p1-stab", 10_296, 1.0, "ok", "pardiso", 0))
    table.loc[1, "integration"] = "nodal"
    goals = analysis.scale_targets(table)
    ratios = goals[goals.target.str.contains("fem-p1p1-stab")]
    assert ratios.measured.tolist() == [1.0, 3.0] and ratios.met.tolist() == ["yes", "**no**"]
    assert "efg nodal pardiso" in ratios["where"].iloc[1]
    growth = goals[goals.target.str.contains("growth")].target.tolist()
    assert any("(paper: " in name for name in growth)
    assert any("(nodal: " in name for name in growth)


def test_exponent_fits_only_the_range_asked_for():
    nodes, seconds = [1_036, 10_296, 100_010, 1_004_276], [1.0, 10.0, 100.0, 1e5]
    assert analysis.exponent(nodes, seconds, within=(1e3, 1e5)) == pytest.approx(
        1.0, abs=0.01)
    assert analysis.exponent(nodes, seconds) > 1.5
    assert analysis.exponent(nodes, [1.0, np.nan, np.nan, 5.0], within=(1e4, 1e6)) != \
        analysis.exponent(nodes, [1.0, np.nan, np.nan, 5.0], within=(1e4, 1e6))  # NaN: 1 point


def test_phase_targets_survive_runs_that_did_not_complete():
    table = _rows(("efg", 10_296, 1.0, "stopped at 240 s", "pardiso", 0),
                  ("fem-p1p1", 10_296, 2.0, "ok", "pardiso", 0))
    goals = analysis.phase_targets(table, pd.DataFrame(), analysis.exponents(table))
    assert goals.met.tolist() == ["not measured"]


def test_run_writes_both_target_tables_the_rates_and_the_figure(tmp_path, monkeypatch):
    monkeypatch.setattr(study, "DGEMM_N", 200)
    monkeypatch.setattr(study, "SHAPES_UP_TO", 0)            # no shape functions
    table = study.run(str(tmp_path / "bench.md"), sizes=[200])
    assert (table.status == "ok").all() and set(table.method) == set(plan.METHODS)
    assert list(table.integration[table.method == "efg"]) == list(plan.SCHEMES) * 2
    assert table[list(runs.COUNTS)].notna().all().all()
    text = (tmp_path / "bench.md").read_text()
    for heading in ("## Targets at scale (EFG step, memory and growth to 10^6 nodes)",
                    "## EFG schemes against fem-p1p1-stab at equal nodes",
                    "## Targets per phase (EFG against FEM)",
                    "## Factorisation rate against dgemm", "## Counts, memory and rates"):
        assert heading in text
    assert "dgemm of two 200 x 200 float64 matrices" in text
    assert (tmp_path / "figures" / "bench.png").stat().st_size > 0
    assert list(pd.read_csv(tmp_path / "tables" / "bench.csv").columns) == list(runs.COLUMNS)


def test_figure_draws_krylov_and_stopped_runs(tmp_path):
    table = _rows(("efg", 10_296, 1.0, "ok", "pardiso", 500.0),
                  ("efg", 300_675, 30.0, "ok", "krylov", 500.0),
                  ("fem-p1p1-stab", 10_296, 0.5, "ok", "pardiso", 0),
                  ("fem-p1p1-stab", 300_675, 0, "stopped at 900 s", "krylov", 0),
                  ("efg", 1_004_276, 0, "died (signal 9)", "krylov", 0))
    report.figure(table, tmp_path / "bench.png")
    assert (tmp_path / "bench.png").stat().st_size > 0
