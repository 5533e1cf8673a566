"""``make bench`` machinery on tiny inputs: children that die or hang, the plan of runs,
the targets' verdicts and the growth fits (no timing is asserted)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from comparisons import bench

ROOT = Path(__file__).parents[1]


def _killed():
    os.kill(os.getpid(), signal.SIGKILL)


def _raises():
    raise RuntimeError("no convergence\nsecond line")


def test_in_child_returns_the_value():
    assert bench.in_child(divmod, 7, 2, timeout=30) == ((3, 1), "ok")


@pytest.mark.parametrize("fn,args,status", [
    (os._exit, (3,), "died (exit 3)"),
    (_killed, (), f"died (signal {int(signal.SIGKILL)})"),
    (_raises, (), "failed: RuntimeError: no convergence"),
])
def test_in_child_reports_a_child_that_gives_no_answer_at_once(fn, args, status):
    tic = time.perf_counter()
    assert bench.in_child(fn, *args, timeout=60) == (None, status)
    assert time.perf_counter() - tic < 20       # not the whole timeout


def test_in_child_stops_a_child_that_hangs():
    tic = time.perf_counter()
    assert bench.in_child(time.sleep, 60, timeout=0.5) == (None, "stopped at 0.5 s")
    assert time.perf_counter() - tic < 20


@pytest.mark.parametrize("sizes", ["1000,abc", "1000,", "1e3,2.5e3,0.5", "50", "nan", "1e400"])
def test_bad_sizes_are_one_line_and_write_nothing(tmp_path, sizes):
    proc = subprocess.run([sys.executable, "-m", "comparisons.cli", "bench", "--sizes", sizes,
                           "--out", str(tmp_path / "bench.md")], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("soilwater: error: --sizes"), proc.stderr
    assert not list(tmp_path.iterdir())


def test_sizes_accept_exponents():
    assert bench.parse_sizes("1000,3e5, 1e6") == [1000, 300_000, 1_000_000]


def test_numpy_blas_names_the_openblas_variables_it_was_loaded_with():
    env = {**os.environ, "OPENBLAS_CORETYPE": "Prescott"}
    env.pop("OPENBLAS_L2_SIZE", None)
    code = "from comparisons import bench; print(bench.numpy_blas())"
    line = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True,
                          capture_output=True, text=True, timeout=120).stdout
    assert "OPENBLAS_CORETYPE Prescott, OPENBLAS_L2_SIZE unset" in line
    if "core " in line and "core unknown" not in line:      # OpenBLAS says which kernel
        assert "Haswell" not in line and "Zen" not in line and "SkylakeX" not in line


def test_dgemm_rates_are_positive_and_mkl_is_measured_where_pardiso_is():
    rates = bench.dgemm(300, repeat=1)
    assert rates["n"] == 300 and rates["numpy_gflops"] > 0
    assert (rates["mkl_gflops"] > 0) == bench.available("pardiso")


def test_make_bench_unsets_the_openblas_variables_before_numpy_loads():
    recipe = (ROOT / "Makefile").read_text().split("\nbench:")[1].split("\n\n")[0]
    line = next(line for line in recipe.splitlines() if "soilwater bench" in line)
    assert all(f"-u {name}" in line.split("soilwater")[0]
               for name in bench.OPENBLAS_VARIABLES)
