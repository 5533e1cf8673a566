"""The consolidation section's figure: Terzaghi isochrones and Mandel's centre pressure."""

import matplotlib.pyplot as plt
import numpy as np

from soilwater.studies.consolidation.study import mandel_centre
from soilwater.studies.harness import figures


def consolidation(terzaghi_table, mandel_table, path, times=(0.1, 0.5, 1.0, 3.0)):
    """Verification: Terzaghi isochrones and Mandel's centre pressure, EFG and FEM.

    Tables from :func:`soilwater.studies.consolidation.study.consolidation_histories`.
    """
    from soilwater.references.closed_forms import terzaghi as series
    from soilwater.references.closed_forms import undrained_pressure
    from soilwater.case.loader import load_case

    case = load_case("terzaghi")
    material, fluid, height = case.material(), case.fluid, case.geometry.height
    args = (height, material.constrained_modulus(), fluid.biot_alpha, fluid.storage,
            fluid.mobility)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.6), constrained_layout=True)
    y = np.linspace(0, height, 101)
    p0 = undrained_pressure(1.0, *args[1:4])                                # unit load
    markers = {"EFG (5 x 41 nodes)": "o", "fem-q1q1": "s", "fem-th": "^",
               "MOOSE Q1/Q1 (peer)": "x"}
    for k, t in enumerate(times):
        exact, _ = series(y, t, 1.0, *args)
        left.plot(exact / p0, y, "-", color=f"C{k}", lw=2, alpha=0.4,
                  label=f"closed form, t = {t:g}")
        for run, marker in markers.items():
            part = terzaghi_table[terzaghi_table.run == run]
            nearest = part.time.iloc[np.argmin(np.abs(part.time.to_numpy() - t))]
            at = part[part.time == nearest]
            left.plot(at.p, at.y, marker, color=f"C{k}", ms=4, mfc="none",
                      label=run if k == 0 else None)
    left.set(xlabel="p$_w$ / p$_0$ (undrained)", ylabel="height above the base (m)",
             title="Terzaghi (peer case A): isochrones")
    left.legend(fontsize=7, loc="lower left")
    for k, (run, part) in enumerate(mandel_table.groupby("run", sort=False)):
        right.semilogx(part.time, part.p_centre, ["o", "s", "^"][k % 3], ms=3, mfc="none",
                       label=run)
    fine = np.geomspace(mandel_table.time.min(), mandel_table.time.max(), 400)
    right.semilogx(fine, mandel_centre(fine), "k-", lw=2, alpha=0.5, label="closed form")
    right.axhline(1.0, color="k", lw=0.5, ls=":")
    right.set(xlabel="time (s)", ylabel="p$_w$ at the centre / (F / 2a)",
              title="Mandel: the Mandel-Cryer rise above the undrained value")
    right.legend(fontsize=8)
    for ax in (left, right):
        ax.grid(alpha=0.3, which="both")
    return figures.save(fig, path)
