"""Where the memory of one Krylov step of the bench case goes.

Quoted by ``docs/studies/krylov.rst`` ("Noise", where the memory goes). The process's
resident and peak memory [MB] (Linux ``/proc``) before the step, once its first tangent
is assembled, once the Krylov preconditioner of that tangent is built (both as Newton's
first iteration has them: the step's system, its residual evaluated, the tangent and
then the preconditioner, :func:`soilwater.linalg.backends.factorise`), and after the
whole step, run afresh once those are dropped.

``python docs/experiments/memory.py --nodes 30000`` (the default; a few minutes on 2
cores).
"""

import gc

from soilwater.linalg.backends import factorise, linear_solver
from soilwater.studies.bench.plan import compression

from common import count, first_system, parsed, parser, solve


def memory(label):
    """Print and return the process's resident and peak memory [MB] (Linux)."""
    with open("/proc/self/status") as fh:
        kb = {line.split(":")[0]: float(line.split()[1]) for line in fh
              if line.startswith(("VmRSS", "VmHWM"))}
    row = {"at": label, "resident_mb": kb["VmRSS"] * 1.024e-3,
           "peak_mb": kb["VmHWM"] * 1.024e-3}
    print(f"  {label:40s} resident {row['resident_mb']:8.0f} MB, peak "
          f"{row['peak_mb']:8.0f} MB", flush=True)
    return row


def main(argv=None):
    """Measure; return the rows of :func:`memory` in order."""
    made = parser(__doc__)
    made.add_argument("--nodes", type=count, default=30_000, help="requested node count")
    with parsed(made, argv) as args:
        case = compression(args.nodes, krylov=True)
        print(f"{len(case.nodes())} nodes, krylov:", flush=True)
        rows = [memory("before the step")]
        with linear_solver("krylov"):
            system, _ = first_system(case, "efg")
            system.residual()
            K = system.tangent()
            rows.append(memory(f"tangent assembled ({K.nnz:.2e} entries)"))
            precondition = factorise(K, system.layout)
            rows.append(memory("preconditioner built"))
            del precondition, K, system
            gc.collect()
            solve(case, "efg")
        rows.append(memory("after the step"))
    return rows


if __name__ == "__main__":
    main()
