"""The partially drained strip footing in the report, measured against the undrained
footing's curves (the saved data of the ``footing`` study)."""

from soilwater.studies.footing_consolidation import study
from soilwater.studies.harness import tables

NAME = "footing-consolidation"
#: The undrained footing's curves come from the ``footing`` study's saved data.
NEEDS = ("footing",)


def run(root, inputs):
    """The tables ``footing_consolidation_curves`` and ``footing_consolidation`` and the
    figure ``footing_consolidation``; returns ``{"footing consolidation"}``."""
    curves = study.curves()
    summary = study.summary(curves, inputs["footing"]["footing curves"])
    tables.write(curves, root / "tables" / "footing_consolidation_curves")
    tables.write(summary, root / "tables" / "footing_consolidation")
    study.figure(curves, root / "figures" / "footing_consolidation.png")
    return {"footing consolidation": summary}


def section(data):
    """The section's markdown lines."""
    return study.section(data["footing consolidation"])
