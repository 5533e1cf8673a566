"""The strip-footing study in the report: every method on every density to 0.5 B, its
load-settlement curves, errors and cost (:mod:`soilwater.studies.footing.study`)."""

from soilwater.studies.footing import study
from soilwater.studies.harness import tables

NAME = "footing"


def run(root, inputs):
    """The tables ``footing_curves`` and ``footing`` and the figures ``footing`` and
    ``footing_cost``; returns ``{"footing curves", "footing", "verdict"}`` (the verdict
    on the paper's claim about large deformation: :func:`~soilwater.studies.footing.
    study.verdict`)."""
    curves = study.curves()
    summary = study.summary(curves)
    tables.write(curves, root / "tables" / "footing_curves")
    tables.write(summary, root / "tables" / "footing")
    study.figure(curves, root / "figures" / "footing.png")
    study.cost_figure(summary, root / "figures" / "footing_cost.png")
    return {"footing curves": curves, "footing": summary,
            "verdict": study.verdict(summary, curves)}


def section(data):
    """The section's markdown lines."""
    return study.section(data["footing"])
