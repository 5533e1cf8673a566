"""Verification of the coupled solvers: Terzaghi (peer case A) with EFG and every FEM
pair against the closed form and MOOSE, and Mandel's centre pressure."""

import numpy as np

from soilwater.studies.consolidation import figures, study
from soilwater.studies.harness import tables
from soilwater.studies.harness.moose import moose_terzaghi

NAME = "consolidation"


def run(root, inputs):
    """The tables ``efg_consolidation``, ``fem_terzaghi`` and ``mandel_centre`` and the
    figure of the histories; returns ``{"efg consolidation", "fem terzaghi", "mandel
    histories"}``."""
    data = {"efg consolidation": study.consolidation(),
            "fem terzaghi": study.fem_terzaghi(moose=moose_terzaghi())}
    terzaghi, data["mandel histories"] = study.consolidation_histories()
    for key, stem in (("efg consolidation", "efg_consolidation"),
                      ("fem terzaghi", "fem_terzaghi"), ("mandel histories", "mandel_centre")):
        tables.write(data[key], root / "tables" / stem)
    figures.consolidation(terzaghi, data["mandel histories"],
                          root / "figures" / "consolidation.png")
    return data


def section(data):
    """The section's markdown lines."""
    ec = data["efg consolidation"].set_index(["method", "case", "metric"]).value
    ft = data["fem terzaghi"].set_index(["method", "steps"])
    mandel = data["mandel histories"]
    return [
        "## Verification: Terzaghi and Mandel",
        "",
        "![consolidation](figures/consolidation.png)",
        "",
        "Terzaghi (peer case A): fem-q1q1 on MOOSE's mesh and steps matches the MOOSE "
        "file to "
        f"{ft.loc[('fem-q1q1', 'moose'), 'moose_pressure_after_0.1']:.1e} p0 for "
        "t >= 0.1, with MOOSE's first-step overshoot ("
        f"{ft.loc[('fem-q1q1', 'moose'), 'overshoot']:.3f}); the stabilised P1/P1 "
        f"removes it ({ft.loc[('fem-p1p1-stab', 'moose'), 'overshoot']:.4f}). On MOOSE's "
        "steps every method is about "
        f"{ft.loc[('fem-th', 'moose'), 'error_p0_after_0.1']:.3f} p0 from the closed "
        "form (backward Euler's time error); with steps capped at 0.01 fem-th is "
        f"{ft.loc[('fem-th', 'dt<=0.01'), 'error_p0_after_0.1']:.4f} p0 away. EFG "
        "(5 x 41 nodes, MOOSE's steps) is " + "; ".join(
            f"{ec.loc[(m, 'terzaghi', 'max_error_load_after_0.1')]:.3f} of the load away "
            "for t >= 0.1 with a settlement error of "
            f"{ec.loc[(m, 'terzaghi', 'settlement_error_after_0.1')] * 100:.2f} % ({m})"
            for m in dict.fromkeys(data["efg consolidation"].method))
        + " (`efg` the recommended configuration, `efg-paper` the paper's). "
        "Mandel: the centre pressure rises to "
        + ", ".join(f"{run} {g.p_centre.max():.3f}" for run, g in mandel.groupby("run"))
        + f" of F/(2a) (closed form {_mandel_peak(mandel):.3f}): the Mandel-Cryer effect.",
        "",
    ]


def _mandel_peak(mandel):
    """The closed form's peak centre pressure, on a fine time grid of its own."""
    return study.mandel_centre(np.geomspace(mandel.time.min(), mandel.time.max(),
                                            400)).max()
