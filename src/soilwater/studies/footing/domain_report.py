"""The strip footing's domain study in the report (:mod:`soilwater.studies.footing.domain`)."""

from soilwater.studies.footing import domain
from soilwater.studies.harness import tables

NAME = "footing-domain"


def run(root, inputs):
    """The tables ``footing_domain_curves`` and ``footing_domain`` and the figure
    ``footing_domain``; returns ``{"footing domain"}``."""
    curves = domain.curves()
    summary = domain.summary(curves)
    tables.write(curves, root / "tables" / "footing_domain_curves")
    tables.write(summary, root / "tables" / "footing_domain")
    domain.figure(curves, root / "figures" / "footing_domain.png")
    return {"footing domain": summary}


def section(data):
    """The section's markdown lines."""
    return domain.section(data["footing domain"])
