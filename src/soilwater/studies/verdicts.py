"""The verdicts on the paper's claims: one table judged on the numbers of several
studies (``NEEDS``), after their sections."""

from soilwater.studies.harness.runs import ERR_NOISE
from soilwater.studies.stability.findings import pair

#: The studies whose saved data the verdicts read.
NEEDS = ("verification", "uniqueness", "stability", "consolidation", "footing",
         "footing-fair", "embankment")


def section(data):
    """The verdicts' lines from the studies' saved data (name -> data); a line naming
    the studies not run yet in place of the table if any is missing."""
    missing = [n for n in NEEDS if n not in data]
    if missing:
        return ["## Verdicts on the paper's claims", "",
                f"*Not judged yet: studies {', '.join(missing)} have not been run.*", ""]
    v, u, s, c = (data[n] for n in ("verification", "uniqueness", "stability",
                                    "consolidation"))
    uc = v["path summary"].set_index(["case", "run"]).loc["unconfined-compression"]
    return claims(uc, u["bifurcation"].set_index("run"), s["infsup slopes"],
                  s["column stability"], s["table2"],
                  c["efg consolidation"].set_index(["method", "case", "metric"]).value,
                  c["fem terzaghi"].set_index(["method", "steps"]),
                  data["footing"]["verdict"], data["footing-fair"]["verdict"]) + [
        embankment(data["embankment"]["summary"]), ""]


def claims(uc, bif, fits, col, t2, ec, ft, foot, fair):
    """The paper's claims, each with its verdict and the measurement behind it."""
    sq, de = (uc.loc[f"EFG, {c}, plain Gauss"] for c in ("squares", "Delaunay"))
    better = sq.err_before > de.err_before and sq.path_error_before > de.path_error_before
    vci = bif.loc[["EFG, square cells", "EFG, Delaunay cells"], "err_before"]
    plain = fits[(fits.method == "efg") & ~fits.weights.str.contains("+", regex=False)
                 & (fits.boundary == "dirichlet")]
    fem = fits.set_index(["method", "boundary"]).slope
    undrained, seeping = (t2[t2.permeability == 0], t2[t2.permeability > 0])
    col5 = col[(col.nodes == "5x41") & (col.permeability > 0)].set_index("method").interior
    return [
        "## Verdicts on the paper's claims",
        "",
        "Each row names the EFG configuration it rests on. `efg-paper` is the paper's: "
        "material state on the nodes, re-interpolated to Delaunay cells rebuilt each step "
        "(`efg.integration = \"paper\"`), penalty conditions, no pressure stabilisation. "
        "`efg` is the recommended one: state at the Gauss points of Lagrangian Delaunay "
        "cells (`gauss`), Nitsche's conditions, the flow-equation perturbation. Both use "
        "quartic weights with scale factor 1.3 and variationally consistent test gradients "
        "(`efg.correction = \"vci\"`; the paper's plain Gauss quadrature where a row "
        "names it).",
        "",
        "| claim | verdict | measured here |",
        "|---|---|---|",
        "| Delaunay background cells are more accurate than square cells (Figs. 4, 6) | "
        + ("supported" if better else "refuted") + " | efg-paper with the paper's plain "
        f"Gauss quadrature, before any loss of uniqueness: ERR {sq.err_before:.2g} (squares) "
        f"against {de.err_before:.2g} (Delaunay), path error {sq.path_error_before:.2g} "
        f"against {de.path_error_before:.2g} p'0. With VCI both are at the Newton noise ("
        + ("below " if vci.max() < ERR_NOISE else "up to ")
        + f"{max(vci.max(), ERR_NOISE):g}): the difference is the quadrature's |",
        "| Some MLS weight combinations and densities give stable equal-order pore "
        "pressures (Table 2): in the inf-sup sense | "
        + ("supported" if plain.stable.any() else "refuted")
        + " | the paper's weights with no pressure stabilisation (the Gauss points of the "
        "first Delaunay cells, where `efg` and `efg-paper` integrate alike): with v = 0 on "
        "the boundary none levels off: last "
        f"slopes {plain.slope.min():.2f} to {plain.slope.max():.2f} (Taylor-Hood "
        f"{fem[('fem-th', 'dirichlet')]:.2f}, P1/P1 {fem[('fem-p1p1', 'dirichlet')]:.2f})"
        + _recommended_infsup(fits) + " |"
        if not plain.stable.any() else
        "| Some MLS weight combinations and densities give stable equal-order pore "
        "pressures (Table 2): in the inf-sup sense | supported | passing: "
        + ", ".join(pair(r) for r in plain[plain.stable].itertuples()) + " |",
        "| ... and in practice, undrained (k = 0, first-step interior pollution, Table 2 "
        "sweep, efg-paper) | " + ("supported for " + ", ".join(
            f"{r.weights} x{r.scale:g}" for r in undrained[
                undrained.rating == "good"].itertuples())
            if (undrained.rating == "good").any() else "refuted: none rates good")
        + f" | {len(undrained)} settings, {undrained.nodes_per_support.min():.0f} to "
        f"{undrained.nodes_per_support.max():.0f} nodes per support: "
        f"{undrained.interior.min():.2g} to {undrained.interior.max():.2g} of the load "
        "(ratings " + "/".join(sorted(set(undrained.rating))) + "); E-A/E-B, the paper's "
        f"good, {undrained[undrained.weights == 'E-A/E-B'].interior.min():.2g} to "
        f"{undrained[undrained.weights == 'E-A/E-B'].interior.max():.2g} |",
        "| ... and at a finite permeability (h²/(c_v dt) = 30, 5 x 41 nodes, efg-paper) "
        "| open | EFG "
        f"{seeping.interior.min():.2g} to {seeping.interior.max():.2g} "
        f"of the load against P1/P1 {col5['fem-p1p1']:.2g} and Taylor-Hood "
        f"{col5['fem-th']:.2g} |",
        "| EFG solves coupled consolidation as accurately as FEM (Terzaghi, Mandel) | "
        "supported | Terzaghi for t >= 0.1: efg "
        f"{ec.loc[('efg', 'terzaghi', 'max_error_load_after_0.1')]:.3f} of the load, "
        f"efg-paper {ec.loc[('efg-paper', 'terzaghi', 'max_error_load_after_0.1')]:.3f}, "
        "fem-th "
        f"{ft.loc[('fem-th', 'moose'), 'error_p0_after_0.1']:.3f} p0 (same steps) |",
        "| EFG handles large, non-uniform deformation where FEM meets mesh distortion "
        "(introduction): at equal vertices | " + " | ".join(foot) + " |",
        "| ... at equal displacement unknowns and at equal run time, smooth and rough | "
        + " | ".join(fair) + " |",
    ]


def embankment(summary):
    """The large-deformation claim's row on a user's geometry: the embankment, every
    method on the same gmsh mesh, raised until it can go no further. Supported if an EFG
    configuration reaches a greater fill than every FEM pair, refuted if a FEM pair
    reaches a greater fill than every EFG configuration, else open."""
    rows = summary.set_index("method")
    efg = rows[rows.index.str.startswith("efg")].fill.max()
    fem = rows[rows.index.str.startswith("fem")].fill.max()
    verdict = ("supported" if efg > fem + 0.05 else "refuted" if fem > efg + 0.05
               else "open")
    return ("| ... on a user's geometry: the embankment on soft clay (same gmsh mesh, "
            "fill raised until a method stops) | " + verdict + " | fill reached: "
            + ", ".join(f"{m} {r.fill:.1f} m ({'to the end' if r.stopped == '-' else r.stopped})"
                        for m, r in rows.iterrows()) + " |")


def _recommended_infsup(fits):
    """The inf-sup result of the recommended configuration's pressure stabilisation (Q/Q,
    scale 1.3, perturbation, v = 0 on the boundary), as a clause."""
    row = fits[(fits.method == "efg") & (fits.weights == "quartic/quartic+perturbation")
               & (fits.boundary == "dirichlet")]
    if row.empty:
        return ""
    row = row.iloc[0]
    outcome = "levels off" if row.stable else "does not level off"
    return f"; the recommended `efg` (perturbation) {outcome}: last slope {row.slope:.2f}"
