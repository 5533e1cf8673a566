"""The soil column's pore-pressure stability: the inf-sup test of every pair, the paper's
Table 2 as a sweep, the built-in column's first steps and skeletons, triangle rules, the
stabilisations' factors and the pressure profiles (Table 2, Fig. 8)."""

from pathlib import Path

from soilwater.diagnostics import figures as infsup_figures
from soilwater.diagnostics import pairs as infsup
from soilwater.studies.harness import tables
from soilwater.studies.stability import figures as stability_figures
from soilwater.studies.stability import findings, study

NAME = "stability"


def run(root, inputs):
    """The section's tables (``infsup``, ``infsup_slopes``, ``column_stability``,
    ``table2``, ``column_ratios``, ``column_skeletons``, ``quadrature_orders``,
    ``stabilisation_factors``, ``target_infsup``, ``column_profiles``) and
    :func:`figures`; returns them under the keys of :func:`section`."""
    data = {"infsup": infsup.report_table(study.INFSUP_SIZES)}
    data["infsup slopes"] = infsup.slopes(data["infsup"])
    data["column stability"] = study.column_stability()
    data["table2"] = study.table2()
    data["column ratios"] = study.column_ratios()
    data["column skeletons"] = study.column_skeletons()
    data["quadrature orders"] = study.quadrature_orders()
    data["stabilisation factors"] = study.stabilisation_factors()
    data["target infsup"] = study.target_infsup(data["stabilisation factors"])
    data["profiles"] = study.column_profiles()
    figures(root, data)
    for key, stem in STEMS.items():
        tables.write(data[key], root / "tables" / stem)
    return data


def figures(root, data):
    """The figures ``infsup``, ``table2`` and ``column_profiles`` under
    ``root/figures``, from :func:`run`'s data; returns their paths."""
    folder = Path(root) / "figures"
    folder.mkdir(parents=True, exist_ok=True)       # the inf-sup figure does not make it
    return [infsup_figures.infsup(data["infsup"], data["infsup slopes"],
                                  folder / "infsup.png"),
            stability_figures.table2(data["table2"], folder / "table2.png"),
            stability_figures.column_profiles(data["profiles"],
                                              folder / "column_profiles.png")]


#: The table of each key of the data: ``tables/STEM``.
STEMS = {"infsup": "infsup", "infsup slopes": "infsup_slopes",
         "column stability": "column_stability", "table2": "table2",
         "column ratios": "column_ratios", "column skeletons": "column_skeletons",
         "quadrature orders": "quadrature_orders",
         "stabilisation factors": "stabilisation_factors",
         "target infsup": "target_infsup", "profiles": "column_profiles"}


def section(data):
    """The section's markdown lines."""
    return [
        "## Soil column: pore-pressure stability (Table 2, Fig. 8)",
        "",
        "![profiles](figures/column_profiles.png)",
        "",
        "Interior pollution (below) of the first step, with the paper's Table 2 "
        "redesigned as a sweep of one factor: the nodes in a support, through the scale "
        "factor (u and p_w alike), printed as the measured mean count at the integration "
        "points, on one grid (5 x 41) and one first step (h²/(c_v dt) = 30 at "
        "k = 1e-5), so the grid aspect and the ratio stay fixed:",
        "",
        "![table2](figures/table2.png)",
        "",
        tables.to_markdown(data["table2"], floatfmt="{:.3g}"),
        findings.table2_findings(data["table2"]),
        "",
        "The built-in column (3 x 21 nodes, k = 1e-5) at first steps with h²/(c_v dt) of "
        "3, 30 and 300:",
        "",
        tables.to_markdown(data["column ratios"], floatfmt="{:.3g}"),
        "The same first step (5 x 41 nodes, 10 s) with the Cam-clay skeleton and with a "
        "linear elastic one of the same initial moduli:",
        "",
        tables.to_markdown(data["column skeletons"].pivot_table(
            index=["permeability", "method"], columns="skeleton",
            values="interior").reset_index(), floatfmt="{:.3g}"),
        "Do exponential weights need a higher triangle rule? Each "
        "combination at Delaunay rules of degree 2, 4 and 6, VCI on:",
        "",
        tables.to_markdown(data["quadrature orders"], floatfmt="{:.3g}"),
        findings.orders_finding(data["quadrature orders"]),
        "",
        *findings.section(data),
    ]
