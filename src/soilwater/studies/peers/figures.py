"""The material section's figure: the stress-point driver's undrained paths."""

import matplotlib.pyplot as plt
import numpy as np

from soilwater.material.driver import closed_form_q, run_test
from soilwater.studies.harness import figures
from soilwater.material.presets import material_from_spec


def stress_paths_driver(path, preset="table1", strain=0.3):
    """q/p'0 against p'/p'0 from the stress-point driver, closed forms drawn over.

    Two panels (undrained plane strain, undrained simple shear), original and modified
    Cam-clay, normally consolidated at p'0.
    """
    tests = {"undrained-plane-strain": "Undrained plane strain (D$_{22}$ = -D$_{11}$)",
             "undrained-simple-shear": "Undrained simple shear (L$_{12}$)"}
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.4), sharey=True, constrained_layout=True)
    for ax, (test, title) in zip(axes, tests.items()):
        for model, colour in (("original", "C0"), ("modified", "C3")):
            clay = material_from_spec({"preset": preset, "model": model})
            table = run_test(clay, test, strain)
            p, q = table.p / clay.p0, table.q / clay.p0
            ax.plot(p, q, color=colour, lw=2, label=f"{model} Cam-clay, driver")
            pc = np.linspace(p.min(), 1.0, 14) * clay.p0
            ax.plot(pc / clay.p0, closed_form_q(clay, pc) / clay.p0, "o", mfc="none",
                    color="k", ms=5, label="closed form" if model == "modified" else None)
        pl = np.array([0.0, 1.05])
        ax.plot(pl, clay.M * pl, "k--", lw=1, label=f"critical state q = {clay.M} p'")
        ax.set(title=f"{title}, to {strain:g} strain", xlabel="p'/p'$_0$",
               xlim=(0, 1.05), ylim=(0, 1.05))
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("q/p'$_0$")
    axes[1].legend(loc="upper left", fontsize=9)
    fig.suptitle("Table 1 clay, normally consolidated: stress-point driver vs closed form")
    return figures.save(fig, path)
