"""Time Cam-clay's numba return mapping against the numpy oracle, and measure their agreement.

Not a test (pytest collects only ``test_*.py``): a script for the return mapping's speed
numbers. From the repository root::

    PYTHONPATH=. python tests/camclay_speed.py                  # 6e5 points, both models
    PYTHONPATH=. python tests/camclay_speed.py --points 100000 --repeat 5
    PYTHONPATH=. python tests/camclay_speed.py --first-call     # compile and cache load

For each model it draws admissible points (:func:`camclay_oracle.admissible_points`, strain
increments up to 2 %: elastic, hardening and softening returns, the original model's
vertex), then times ``CamClay.update`` (numba kernel) and ``camclay_oracle.update`` (numpy),
interleaved, best of ``--repeat``, in one process, so that the ratio is what counts on a
shared machine (wall-clock and CPU time). It also times the numpy part of ``update``
(rotation, elastic trial) and the kernel alone, on one thread and on the pool of
:mod:`soilwater.linalg.threads` (checking that both give the same arrays), and reports the largest
differences of kernel and oracle: stress over the start-of-step p', tangent over its
Frobenius norm, p'c relative.

``--first-call`` runs a fresh interpreter twice, timing the import and the first
``update``: with an empty numba cache (compilation), then with the cache that run wrote
(loading).

Measured on the idle 2-core development machine, 6e5 points, numba 0.68.1, numpy 2.4.6,
best of 5: ``update`` took 0.35 s wall-clock (0.60 s CPU) for the original model and 0.36 s
(0.59 s) for the modified one against the oracle's 3.04 s and 2.41 s, wall-clock ratios
8.7 and 6.7 (CPU 5.3 and 4.2); the kernel alone took 0.44 s on one thread and 0.22 s on
two (1.99 and 1.91 times faster), the numpy part 0.09 s. Largest differences: stress
2.5e-11 p'_n, tangent 1.5e-9 of its norm (original; 3.6e-11 modified), p'c 1.9e-11.
(While the cores were shared with other jobs, numba's ``prange`` had given no gain one
could rely on: ratios 0.84 to 1.54.) First call: 8.0 s of CPU to compile with an empty
cache, 0.6 s to load from it.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

import camclay_oracle as oracle  # noqa: E402
from soilwater.material import camclay_kernel as camclay  # noqa: E402
from soilwater.material.camclay import CamClay  # noqa: E402
from soilwater.linalg.threads import threads, using  # noqa: E402
from soilwater.material.kinematics import (  # noqa: E402
    DEVIATORIC, deviator, double_dot, hughes_winget, invariants)


def table1(model):
    """The paper's Table 1 clay."""
    return CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0, model=model)


def one_thread(fn, *args):
    """``fn(*args)`` on one thread (:func:`soilwater.linalg.threads.using`)."""
    with using(1):
        return fn(*args)


def kernel_arguments(clay, stress, state, dstrain, dspin):
    """The arguments ``CamClay.update`` hands to the kernel (its numpy part)."""
    stress = hughes_winget(stress, dspin)
    p_n, _ = invariants(stress)
    _, G = clay.moduli(p_n, state["v"])
    s_tr = deviator(stress) + 2 * G[:, None] * (dstrain @ DEVIATORIC.T)
    q_tr = np.sqrt(1.5 * double_dot(s_tr, s_tr))
    return (clay.constants, s_tr, q_tr, p_n, state["pc"], state["v"],
            dstrain[:, :3].sum(axis=1), G, 1e-11, 60)


def best(calls, repeat):
    """Best wall-clock and best CPU time [s] of each call over ``repeat`` interleaved
    rounds, and the last results. CPU time is what a serial call costs whatever else the
    machine runs; wall time is what ``prange`` can shorten."""
    wall, cpu = [np.inf] * len(calls), [np.inf] * len(calls)
    results = [None] * len(calls)
    for _ in range(repeat):
        for k, call in enumerate(calls):
            start, start_cpu = time.perf_counter(), time.process_time()
            results[k] = call()
            cpu[k] = min(cpu[k], time.process_time() - start_cpu)
            wall[k] = min(wall[k], time.perf_counter() - start)
    return wall, cpu, results


def agreement(points, kernel, numpy):
    """Largest differences of the kernel's (stress, state, tangent) from the oracle's."""
    p_n = invariants(hughes_winget(points[0], points[3]))[0]
    norm = np.linalg.norm(numpy[2], axis=(1, 2))
    return {"stress / p'_n": (np.abs(kernel[0] - numpy[0]).max(axis=1) / p_n).max(),
            "tangent / |C|": (np.linalg.norm(kernel[2] - numpy[2], axis=(1, 2)) / norm).max(),
            "p'c rel": np.abs(kernel[1]["pc"] / numpy[1]["pc"] - 1).max()}


def kinds(points, result):
    """Counts of elastic, hardening, softening and vertex returns."""
    pc_n, pc = points[1]["pc"], result[1]["pc"]
    q = invariants(result[0])[1]
    return {"elastic": int(np.sum(pc == pc_n)), "hardening": int(np.sum(pc > pc_n)),
            "softening": int(np.sum(pc < pc_n)), "vertex": int(np.sum((q == 0) & (pc != pc_n)))}


def compare(model, n, repeat, seed):
    """Print timings and agreement of one model at n points."""
    clay = table1(model)
    points = oracle.admissible_points(clay, np.random.default_rng(seed).random(
        (n, oracle.UNIFORMS)))
    args = kernel_arguments(clay, *points)
    camclay.return_mapping(*(a[:10] if isinstance(a, np.ndarray) else a for a in args))
    wall, cpu, (kernel, numpy, _, serial, parallel) = best(
        [lambda: clay.update(*points), lambda: oracle.update(clay, *points),
         lambda: kernel_arguments(clay, *points),
         lambda: one_thread(camclay.return_mapping, *args),
         lambda: camclay.return_mapping(*args)], repeat)
    assert all(np.array_equal(serial[k], parallel[k]) for k in range(4))
    print(f"{model}, {n} points, best of {repeat}, {threads()} threads; seconds wall (cpu)")
    for k, label in enumerate(["update (numba kernel)", "numpy oracle", "  numpy part of update",
                               "  kernel, one thread", "  kernel, threads"]):
        print(f"  {label:24s} {wall[k]:7.3f} ({cpu[k]:7.3f})")
    print(f"  oracle / update: wall {wall[1] / wall[0]:.1f}, cpu {cpu[1] / cpu[0]:.1f}; "
          f"one thread / threads wall {wall[3] / wall[4]:.2f}")
    differences = agreement(points, kernel, numpy)
    print("  largest differences:", ", ".join(f"{k} {v:.2e}" for k, v in differences.items()))
    print("  returns:", kinds(points, numpy))


FIRST_CALL = """
import time; start, start_cpu = time.perf_counter(), time.process_time()
import numpy as np
from soilwater.material.camclay import CamClay
clay = CamClay(lam=0.11, kappa=0.04, M=1.42, nu=0.333, e0=0.83, p0=3.0)
imported, imported_cpu = time.perf_counter(), time.process_time()
stress, state = clay.initial_state(10)
clay.update(stress, state, np.full((10, 4), 1e-3), np.zeros(10))
print(f"import {imported - start:.2f} s ({imported_cpu - start_cpu:.2f} s cpu), first update "
      f"{time.perf_counter() - imported:.2f} s ({time.process_time() - imported_cpu:.2f} s cpu)")
"""


def first_call():
    """Time import and first update in fresh interpreters: cold numba cache, then warm."""
    with tempfile.TemporaryDirectory() as empty:
        for label, env in (("empty cache (compiles)", {"NUMBA_CACHE_DIR": empty}),
                           ("cache written above (loads)", {"NUMBA_CACHE_DIR": empty})):
            out = subprocess.run([sys.executable, "-c", FIRST_CALL], capture_output=True,
                                 text=True, check=True, env={**os.environ, **env})
            print(f"{label}: {out.stdout.strip()}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=600_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=17)
    parser.add_argument("--models", nargs="+", default=["original", "modified"])
    parser.add_argument("--first-call", action="store_true")
    options = parser.parse_args()
    if options.first_call:
        first_call()
        return
    for model in options.models:
        compare(model, options.points, options.repeat, options.seed)


if __name__ == "__main__":
    main()
