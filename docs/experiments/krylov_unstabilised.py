"""The bench step on the Krylov back-end without and with EFG's pressure stabilisation.

Quoted by ``docs/studies/krylov.rst`` ("A stabilised pressure at k = 0"). The bench step
(:func:`soilwater.studies.bench.plan.compression`, EFG with Nitsche's conditions) with
each ``efg.stabilisation``: Newton and FGMRES iterations, or the failure.

``python docs/experiments/krylov_unstabilised.py --nodes 3000`` (the default; under a
minute on 2 cores).
"""

from soilwater.case.loader import load_case
from soilwater.errors import ConvergenceError
from soilwater.linalg.backends import linear_solver
from soilwater.studies.bench.plan import compression

from common import count, parsed, parser, solve


def main(argv=None):
    """Run the step per stabilisation; return one row each (``failed``: the error, or
    None)."""
    made = parser(__doc__)
    made.add_argument("--nodes", type=count, default=3_000, help="requested node count")
    made.add_argument("--stabilisations", nargs="+", default=["none", "perturbation"],
                      help="values of efg.stabilisation")
    rows = []
    with parsed(made, argv) as args:
        for kind in args.stabilisations:
            case = load_case(compression(args.nodes, krylov=True),
                             f'efg.stabilisation="{kind}"')
            row = {"stabilisation": kind, "failed": None}
            label = f"{args.nodes} nodes, stabilisation {kind}"
            with linear_solver("krylov"):
                try:
                    s = solve(case, "efg").summary
                except ConvergenceError as err:
                    print(f"{label}: failed: {err}", flush=True)
                    rows.append({**row, "failed": str(err)})
                    continue
            row.update(newton=s["newton_iterations"], fgmres=s["linear_iterations"],
                       cutbacks=s["cutbacks"])
            print(f"{label}: Newton {row['newton']}, FGMRES {row['fgmres']}, cut-backs "
                  f"{row['cutbacks']}", flush=True)
            rows.append(row)
    return rows


if __name__ == "__main__":
    main()
