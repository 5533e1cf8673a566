"""Page faults and system time of one Krylov step, with transparent huge pages on and off.

Quoted by ``docs/studies/krylov.rst`` ("Noise"). Per size, one Krylov step of the bench
case (:func:`soilwater.studies.bench.runs.one_step`) with transparent huge pages as the
system has them and off for the process (Linux ``prctl(PR_SET_THP_DISABLE)``): step
time, user and system CPU time and the step's minor page faults; then, in a process of
its own, the minor faults of building the step's first preconditioner on its first
tangent (:func:`soilwater.linalg.backends.factorise`). With huge pages off each fault is
4 kB of freshly touched memory. Every measurement runs in its own forked process.

``python docs/experiments/faults.py 100000`` (the default size; a few minutes on 2
cores; Linux).
"""

import ctypes
import resource

from soilwater.linalg.backends import factorise, linear_solver
from soilwater.studies.bench.plan import compression
from soilwater.studies.bench.runs import in_child, one_step

from common import LIMIT, count, first_system, parsed, parser

#: ``prctl``'s option that turns transparent huge pages off for the process.
PR_SET_THP_DISABLE = 41


def _pages(huge_pages):
    """Transparent huge pages off for this process unless ``huge_pages``."""
    if not huge_pages:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0)


def faulting_step(nodes, huge_pages):
    """One Krylov step: step [s], user and system CPU [s] and minor faults."""
    _pages(huge_pages)
    before = resource.getrusage(resource.RUSAGE_SELF)
    row = one_step("efg", nodes, "cam-clay", "krylov")
    after = resource.getrusage(resource.RUSAGE_SELF)
    return {"step": row["step"], "user": after.ru_utime - before.ru_utime,
            "system": after.ru_stime - before.ru_stime,
            "faults": after.ru_minflt - before.ru_minflt}


def faulting_build(nodes, huge_pages):
    """Minor faults of building the Krylov preconditioner of the step's first tangent."""
    _pages(huge_pages)
    system, _ = first_system(compression(nodes, krylov=True), "efg")
    system.residual()
    K = system.tangent()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    with linear_solver("krylov"):
        factorise(K, system.layout)
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


def main(argv=None):
    """Measure; return one row per size and huge-page setting (``status``: ``"ok"`` or
    why a run did not finish)."""
    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[100_000],
                      help="requested node counts")
    made.add_argument("--limit", type=float, default=LIMIT, help="seconds per process")
    rows = []
    with parsed(made, argv) as args:
        one_step("efg", 200, "cam-clay", "krylov")          # numba's caches, outside the runs
        for nodes in args.sizes:
            for huge_pages in (True, False):
                label = f"{nodes} nodes, huge pages {'as set' if huge_pages else 'off'}"
                step, status = in_child(faulting_step, nodes, huge_pages,
                                        timeout=args.limit)
                built, built_status = in_child(faulting_build, nodes, huge_pages,
                                               timeout=args.limit)
                row = {"nodes": nodes, "huge_pages": huge_pages, "status": status,
                       "build_status": built_status, **(step or {}), "build_faults": built}
                rows.append(row)
                if status != "ok" or built_status != "ok":
                    print(f"{label}: {status}, build {built_status}", flush=True)
                    continue
                fresh = ("" if huge_pages else f"; {row['faults'] * 4096e-9:.1f} and "
                         f"{built * 4096e-9:.1f} GB of fresh memory")
                print(f"{label}: step {row['step']:.1f} s, user {row['user']:.1f} s, "
                      f"system {row['system']:.1f} s, faults {row['faults']:.3g} (first "
                      f"build {built:.3g}{fresh})", flush=True)
    return rows


if __name__ == "__main__":
    main()
