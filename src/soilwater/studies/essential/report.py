"""Penalty against Nitsche's method in the report: accuracy on the verification cases
and the near-singular confined tangent (:mod:`soilwater.studies.essential.study`,
:mod:`soilwater.studies.essential.tangent`)."""

from soilwater.studies.essential import study, tangent
from soilwater.studies.harness import tables

NAME = "essential"


def run(root, inputs):
    """The tables ``essential_accuracy`` and ``essential_confined``; returns
    ``{"essential", "confined"}``."""
    data = {"essential": study.accuracy(), "confined": tangent.confined()}
    tables.write(data["essential"], root / "tables" / "essential_accuracy")
    tables.write(data["confined"], root / "tables" / "essential_confined")
    return data


def section(data):
    """The section's markdown lines."""
    return study.section(data["essential"], data["confined"])
