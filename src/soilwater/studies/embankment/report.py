"""The embankment on soft clay in the report (:mod:`soilwater.studies.embankment.study`)."""

from soilwater.studies.embankment import study
from soilwater.studies.harness import tables

NAME = "embankment"


def run(root, inputs):
    """The tables ``embankment_curves``, ``embankment`` and ``embankment_first_stage`` and
    the figures ``embankment`` and ``embankment_deformed``; returns ``{"summary",
    "first stage"}``."""
    results = study.runs()
    curves = study.curves(results)
    summary = study.summary(curves, results)
    check = study.first_stage()
    tables.write(curves, root / "tables" / "embankment_curves")
    tables.write(summary, root / "tables" / "embankment")
    tables.write(check, root / "tables" / "embankment_first_stage")
    study.figure(curves, root / "figures" / "embankment.png")
    study.deformed(results, root / "figures" / "embankment_deformed.png")
    return {"summary": summary, "first stage": check}


def section(data):
    """The section's markdown lines."""
    return study.section(data["summary"], data["first stage"])
