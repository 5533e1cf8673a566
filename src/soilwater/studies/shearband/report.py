"""The rough-platen compression's shear band in the report
(:mod:`soilwater.studies.shearband.study`)."""

from soilwater.studies.harness import tables
from soilwater.studies.shearband import study

NAME = "shearband"


def run(root, inputs):
    """The tables ``shearband_curves``, ``shearband`` and ``shearband_robustness`` and the
    figure ``shearband``; returns ``{"shearband prediction", "shearband", "shearband
    robustness"}``."""
    runs, predicted = study.runs(), study.prediction()
    curves = study.curves(runs)
    data = {"shearband prediction": predicted,
            "shearband": study.summary(curves, predicted),
            "shearband robustness": study.robustness(runs)}
    tables.write(curves, root / "tables" / "shearband_curves")
    tables.write(data["shearband"], root / "tables" / "shearband")
    tables.write(data["shearband robustness"], root / "tables" / "shearband_robustness")
    study.figure(runs, curves, predicted, root / "figures" / "shearband.png")
    return data


def section(data):
    """The section's markdown lines."""
    return study.section(data)
