"""Nitsche's eigenvalue bound on boundary strips of 0 to 3 neighbour rings against the
whole domain's (:func:`soilwater.efg.essential.nitsche.largest_eigenvalue`), on the
cantilever.
"""

import numpy as np
import pandas as pd

from soilwater.efg.essential import nitsche
from soilwater.efg import quadrature
from soilwater.efg import statics
from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.efg.mls import ShapeFunctions
from soilwater.case.loader import load_case


def eigenvalue_strips(levels=((13, 4), (25, 7), (49, 13), (97, 25)), rings=(0, 1, 2, 3)):
    """The cantilever's eigenvalue bound lambda (times h/M) on strips of ``rings``
    neighbour rings and on the whole domain (``exact``), per refinement.

    Returns
    -------
    pandas.DataFrame
        ``nodes``, ``rings_R`` per ring count and ``exact``: ``lambda h / M``
        (dimensionless; M the P-wave modulus, h the smallest spacing).
    """
    rows = []
    for nx, ny in levels:
        case = load_case("cantilever", [f"discretisation.nx={nx}", f"discretisation.ny={ny}"])
        domain, boundary = _static_bound(case)
        scale = min(case.spacing) / case.material().constrained_modulus()
        row = {"nodes": nx * ny}
        for r in (*rings, None):
            row["exact" if r is None else f"rings_{r}"] = scale * nitsche.largest_eigenvalue(
                domain, boundary, rings=r)
        rows.append(row)
    return pd.DataFrame(rows)


def _static_bound(case):
    """``(domain, boundary)`` arguments of
    :func:`soilwater.efg.essential.nitsche.largest_eigenvalue` for a static case's elastic
    operator and constrained components."""
    s, material = case.efg, case.material()
    nodes, loop = case.nodes(), case.boundary_loop()
    quad = quadrature.background(case, nodes, loop, s)
    shape = ShapeFunctions.build(nodes, quad.points, s.weight_u, s.scale_u)
    bp = boundary_points(nodes, loop, segment_edges(nodes, loop, case.geometry))
    shape_b = ShapeFunctions.build(nodes, bp.points, s.weight_u, s.scale_u)
    constrained, *_ = statics.boundary_data(case, bp, case.exact_solution())
    K, G = material.moduli()
    D_b, D = (nitsche.gradient_operator(nitsche.isotropic(np.full(m, K), np.full(m, G)))
              for m in (len(bp.weights), len(quad.weights)))
    return ((shape, quad.weights, D),
            (shape_b, bp.weights, nitsche.flux_operator(bp, constrained, D_b)))
