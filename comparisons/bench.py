"""``make bench``: speed as ratios against scikit-fem in the same run (never timed tests).

So far: EFG shape functions and gradients against scikit-fem ``CellBasis`` construction
for the same number of quadrature points (P1 triangles on the Delaunay triangulation of
the same nodes, 3-point rule, so both evaluate at the same points).
"""

import time

import numpy as np
import pandas as pd
import skfem

from efg.mls import ShapeFunctions
from efg.quadrature import delaunay_cells
from soil.problems import load_case


def best_of(fn, repeat=3):
    """Best wall time [s] of ``repeat`` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        tic = time.perf_counter()
        fn()
        times.append(time.perf_counter() - tic)
    return min(times)


def shape_functions(n_side=183, weight="quartic", scale=1.3):
    """Time MLS shape functions + gradients and scikit-fem basis construction.

    Parameters
    ----------
    n_side : int
        Nodes per side of the square grid (183 gives ~2e5 quadrature points).

    Returns
    -------
    pandas.DataFrame
        One row: nodes, points, both times [s] and their ratio EFG / scikit-fem.
    """
    case = load_case("patch-test", [f"discretisation.nx={n_side}",
                                    f"discretisation.ny={n_side}"])
    nodes = case.nodes()
    quad = delaunay_cells(nodes, nodes[case.boundary_loop()], order=2)
    efg = best_of(lambda: ShapeFunctions.build(nodes, quad.points, weight, scale))
    mesh = skfem.MeshTri(np.ascontiguousarray(nodes.T), np.ascontiguousarray(quad.triangles.T))
    rows = []
    for name, element in (("P1", skfem.ElementTriP1()), ("P2", skfem.ElementTriP2())):
        fem = best_of(lambda: skfem.CellBasis(mesh, element, intorder=2))
        rows.append({"phase": f"shape functions + gradients vs CellBasis({name})",
                     "nodes": len(nodes), "points": len(quad.weights), "efg_s": efg,
                     "skfem_s": fem, "ratio": efg / fem, "target": 1.5})
    return pd.DataFrame(rows)


def run(path="reports/bench.md"):
    """Run every benchmark, print the table and write it as Markdown."""
    from comparisons.tables import to_markdown

    table = shape_functions()
    text = ("# Benchmarks\n\nRatios EFG / scikit-fem measured in one run on this machine "
            "(best of 3 after a warm-up).\n\n" + to_markdown(table))
    with open(path, "w") as fh:
        fh.write(text)
    print(text)
    return table
