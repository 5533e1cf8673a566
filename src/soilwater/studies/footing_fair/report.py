"""The fair large-deformation comparison on the strip footing in the report
(:mod:`soilwater.studies.footing_fair.study`)."""

from soilwater.studies.footing_fair import study
from soilwater.studies.harness import tables

NAME = "footing-fair"


def run(root, inputs):
    """The tables ``footing_fair_curves``, ``footing_fair_reference``, ``footing_fair``
    and ``footing_fair_pairs`` and the figures ``footing_fair`` and
    ``footing_fair_cost``; returns ``{"fair reference", "fair", "fair pairs", "verdict"}`` (the verdict
    on the paper's claim about large deformation at equal unknowns and run time:
    :func:`~soilwater.studies.footing_fair.study.verdict`)."""
    curves = study.curves()
    ref = study.reference(curves)
    summary = study.summary(curves, ref)
    paired = study.pairs(summary)
    for frame, stem in ((curves, "footing_fair_curves"), (ref, "footing_fair_reference"),
                        (summary, "footing_fair"), (paired, "footing_fair_pairs")):
        tables.write(frame, root / "tables" / stem)
    study.figure(curves, ref, root / "figures" / "footing_fair.png")
    study.cost_figure(summary, root / "figures" / "footing_fair_cost.png")
    return {"fair reference": ref, "fair": summary, "fair pairs": paired,
            "verdict": study.verdict(paired)}


def section(data):
    """The section's markdown lines."""
    return study.section(data["fair"], data["fair reference"], data["fair pairs"])
