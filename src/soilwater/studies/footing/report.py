"""The strip-footing study in the report: every method on every density to 0.5 B, its
load-settlement curves, errors and cost (:mod:`soilwater.studies.footing.study`)."""

from pathlib import Path

from soilwater.studies.footing import figures as footing_figures
from soilwater.studies.footing import study
from soilwater.studies.harness import tables

NAME = "footing"


def run(root, inputs):
    """The tables ``footing_curves`` and ``footing`` and the figures of :func:`figures`;
    returns ``{"footing curves", "footing", "verdict"}`` (the verdict on the paper's
    claim about large deformation: :func:`~soilwater.studies.footing.study.verdict`)."""
    curves = study.curves()
    summary = study.summary(curves)
    tables.write(curves, root / "tables" / "footing_curves")
    tables.write(summary, root / "tables" / "footing")
    data = {"footing curves": curves, "footing": summary,
            "verdict": study.verdict(summary, curves)}
    figures(root, data)
    return data


def figures(root, data):
    """The figures ``footing`` (how far each method gets), ``footing_convergence`` (its
    curves as the nodes are refined) and ``footing_cost`` under ``root/figures``, from
    :func:`run`'s data; returns their paths."""
    folder = Path(root) / "figures"
    curves = data["footing curves"]
    return [footing_figures.reach(curves, folder / "footing.png"),
            footing_figures.convergence(curves, folder / "footing_convergence.png"),
            footing_figures.cost(data["footing"], folder / "footing_cost.png")]


def section(data):
    """The section's markdown lines."""
    return study.section(data["footing"])
