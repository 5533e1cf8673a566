"""The report's pore-pressure stability section: the inf-sup test, the column's boundary
layer and interior, the Table 2 sweep's findings and the rule degrees (text from the
tables of the same run)."""

import numpy as np

from soilwater.diagnostics import pairs as infsup
from soilwater.studies.harness import metrics
from soilwater.studies.harness import tables
from soilwater.studies.stability.study import TARGET
from soilwater.diagnostics import infsup as soil_infsup


def section(data):
    """The inf-sup test of every pair and the column's boundary layer and interior."""
    fits, col = data["infsup slopes"], data["column stability"]
    last = data["infsup"][data["infsup"].n == data["infsup"].n.max()]
    summary = fits.merge(last[["method", "weights", "scale_u", "scale_p", "boundary",
                               "beta", "zero_modes"]],
                         on=["method", "weights", "scale_u", "scale_p", "boundary"])
    passing = sorted({pair(r) for r in fits[fits.stable].itertuples()})
    undrained = col[col.permeability == 0].pivot(index="method", columns="nodes",
                                                 values="interior")
    return [
        "### Inf-sup test and interior pollution",
        "",
        "![infsup](figures/infsup.png)",
        "",
        "The numerical inf-sup test of Chapelle and Bathe (`soilwater infsup`) on a unit "
        "square of n x n grid nodes, on each method's own shape functions and "
        "quadrature, with v free and with v = 0 on the boundary (zero-mean pressures). "
        "A pair passes when beta levels off: on n = "
        f"{', '.join(str(n) for n in sorted(set(data['infsup'].n)))}, the local slope "
        f"of log beta against log h at most {infsup.LEVEL_SLOPE:g} over each of the last "
        "two refinements. That slope (the larger), and beta and zero modes at the finest "
        "size:",
        "",
        tables.to_markdown(summary, floatfmt="{:.3g}"),
        "Where beta stays near "
        f"{np.sqrt(soil_infsup.ZERO):.0e} (EFG with v = 0), it is the resolution of the "
        f"zero-mode threshold (eigenvalues below {soil_infsup.ZERO:g} of the largest): "
        "the spectrum has no gap, the pair no inf-sup constant. "
        "Passing both variants: " + (", ".join(
            p for p in passing if (fits[fits.apply(pair, axis=1) == p].stable.all()))
            or "none") + ".",
        "",
        "First-step pore pressure of the soil column, split into the boundary layer "
        f"(within {metrics.LAYER:g} m of the drained top: overshoot over the load) and "
        "the interior (deeper: the largest |p - p_ref| at any node over the load, p_ref "
        "Terzaghi's series at the initial stiffness, or the undrained pressure at "
        "k = 0), under refinement with the first step scaled with h^2 (h^2/(c_v dt) = 30 "
        f"at k = 1e-5). Rating: good up to {metrics.GOOD:g} (just above Taylor-Hood's "
        f"worst), bad beyond {metrics.BAD:g} (P1/P1 at k = 0), fair between:",
        "",
        tables.to_markdown(col, floatfmt="{:.3g}"),
        "Interior pollution at k = 0 (undrained) by method and grid:",
        "",
        tables.to_markdown(undrained.reset_index(), floatfmt="{:.3g}"),
        "With the flow-equation perturbation (`efg.stabilisation = \"perturbation\"`, "
        "the beta = h²/(4M) of fem-p1p1-stab) the undrained interior pollution of EFG "
        "Q/Q falls from "
        + ", ".join(f"{undrained.loc['efg Q/Q', n]:.3g}" for n in undrained.columns)
        + " to " + ", ".join(f"{undrained.loc['efg Q/Q, perturbation', n]:.3g}"
                             for n in undrained.columns)
        + f" on {', '.join(undrained.columns)} nodes; fem-p1p1-stab reaches "
        + ", ".join(f"{undrained.loc['fem-p1p1-stab', n]:.3g}" for n in undrained.columns)
        + ". With the polynomial pressure projection on the background cells "
        "(`efg.stabilisation = \"projection\"`, Dohrmann and Bochev's term with "
        "tau = 1/G) it falls to "
        + ", ".join(f"{undrained.loc['efg Q/Q, projection', n]:.3g}"
                    for n in undrained.columns)
        + ". Each multiplied by `efg.stabilisation_factor` (default 1), against "
        "Terzaghi's error (5 x 41, t >= 0.1) and the inf-sup test (v = 0):",
        "",
        tables.to_markdown(data["stabilisation factors"], floatfmt="{:.3g}"),
        factors_finding(data["stabilisation factors"], data["target infsup"]),
        "",
    ]


def factors_finding(factors, refined, target=TARGET):
    """Per stabilisation: the smallest factor bringing the 5 x 41 column below
    ``target`` and what it costs (``refined``: :func:`soilwater.studies.verification.study.
    target_infsup`)."""
    lines = []
    for kind, part in factors.groupby("stabilisation", sort=False):
        one, below = part.set_index("factor").loc[1], part[part["interior_5x41"] < target]
        if below.empty:
            best = part.loc[part["interior_5x41"].idxmin()]
            lines.append(f"No {kind} factor brings the 5 x 41 interior below {target:g} "
                         f"of the load (least {best['interior_5x41']:.3g}, at factor "
                         f"{best.factor:g}).")
            continue
        first = below.iloc[0]
        more = refined[refined.stabilisation == kind]
        lines.append(
            f"The smallest {kind} factor bringing the 5 x 41 interior below {target:g} of "
            f"the load is {first.factor:g} ({first['interior_5x41']:.3g}); it moves "
            f"Terzaghi's error from {one.terzaghi:.4f} to {first.terzaghi:.4f} and the "
            f"inf-sup slope from {one.slope:.2f} to {first.slope:.2f} on n <= 33, where beta "
            f"still falls (it is highest on coarse grids). One refinement further, n = "
            + ", ".join(f"{r.n}: beta {r.beta:.3g}" for r in more.itertuples())
            + f", slope {more.slope.iloc[0]:.2f}: it "
            + ("levels off" if more.stable.iloc[0] else "does not level off")
            + f" by the {infsup.LEVEL_SLOPE:g} rule.")
    return " ".join(lines) + (" The default factor stays 1, each term's published "
                              "coefficient: no factor was chosen to meet a target.")


def table2_findings(t2):
    """What the Table 2 sweep shows, per permeability: the best EFG setting and the
    ratings of the paper's 'good' combination."""
    lines = []
    for k, part in t2.groupby("permeability"):
        best = part.loc[part.interior.idxmin()]
        eaeb = part[part.weights == "E-A/E-B"]
        lines.append(
            f"At k = {k:g}: the least interior pollution is {best.interior:.3g} "
            f"({best.weights} at scale {best.scale:g}, {best.nodes_per_support:.0f} nodes "
            "per support); ratings " + ", ".join(
                f"{r}: {n}" for r, n in part.rating.value_counts().sort_index().items())
            + ". The paper's good E-A/E-B at high density rates "
            + " to ".join(dict.fromkeys(eaeb.sort_values("scale").rating)) + f" here "
            f"({eaeb.interior.min():.3g} to {eaeb.interior.max():.3g}).")
    return " ".join(lines)


def orders_finding(orders, gain=0.1):
    """Whether a higher rule helps the exponential weights systematically: a measure that
    falls by more than ``gain`` for every exponential combination."""
    measures = ["interior_k0", "interior_k1e-5", "terzaghi", "patch", "cantilever"]
    exp = orders[orders.weights != "Q/Q"].set_index(["weights", "order"])[measures]
    base = exp.xs(orders.order.min(), level="order")
    helped = [f"{m} at degree {o}" for o in sorted(set(orders.order)) if o > orders.order.min()
              for m in measures
              if (exp.xs(o, level="order")[m] < (1 - gain) * base[m]).all()]
    spread = orders.groupby("weights")[measures].agg(lambda v: v.max() / v.min() - 1).max()
    return ("Across the rules the largest relative change per combination is "
            + ", ".join(f"{c} {v * 100:.0f} %" for c, v in spread.items()) + ". "
            + ("A higher rule lowers, for every exponential combination by more than "
               f"{gain * 100:.0f} %: " + ", ".join(helped) if helped else
               "No measure falls by more than "
               f"{gain * 100:.0f} % for every exponential combination at a higher rule: "
               "they do not need one, and the default stays degree 2") + ".")


def pair(row):
    """A pair's name in the inf-sup table: the FEM method, or EFG with its settings."""
    if row.method != "efg":
        return row.method
    return f"efg {row.weights} scale {row.scale_u:g}/{row.scale_p:g}"
