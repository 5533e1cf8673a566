"""
The soil column: pore pressure after the first step
===================================================

``soil-column`` (paper Fig. 8, after Zienkiewicz et al. 1986) is a 1 x 10 m column of
the Table 1 clay (3 x 21 nodes, k = 1e-5 m/s) under a 1 kPa step load on its drained
top. Just after loading the column is undrained, p_w equals the load everywhere, and it
drops to zero in a thin layer at the top. The first step (40 s) is too short for that
layer to span an element: h^2 / (c_v dt) is about 30 (printed below), well above the
ratio of about 6 below which a first step is free of pressure oscillations. Any
discretisation then overshoots the load near the drained top; interpolating u and p_w
with the same order, as P1/P1 FEM does and as EFG does (both fields live on the same
nodes), adds the spurious pressure modes that the inf-sup condition rules out for
Taylor-Hood FEM (P2/P1).

The paper's Table 2 claims that EFG's pressure is stable with the weight E-A
(exponential, c = 0.5) for u and the sharper E-B (c = 0.25) for p_w. The weight pairs
Q/Q (quartic), E-A/E-A and E-A/E-B are compared with P1/P1 and Taylor-Hood FEM by the
overshoot (max p_w / load - 1) and the oscillation index (total variation of p_w along
the axis beyond that of a monotone profile, over the load; zero when monotone). EFG runs
as method ``efg-paper``, the paper's configuration, with no pressure stabilisation (the
recommended ``efg`` adds one: the stability study measures what it changes).
"""

# %%
import matplotlib.pyplot as plt
import pandas as pd

import soilwater
from soilwater.studies.harness.metrics import axis_profile, oscillation_index, overshoot
from soilwater.studies.stability.study import stability_number

RUNS = {"EFG Q/Q": ("efg-paper", ("efg.weight_u=quartic", "efg.weight_p=quartic")),
        "EFG E-A/E-A": ("efg-paper", ("efg.weight_u=exp:0.5", "efg.weight_p=exp:0.5")),
        "EFG E-A/E-B": ("efg-paper", ("efg.weight_u=exp:0.5", "efg.weight_p=exp:0.25")),
        "FEM p1p1": ("fem-p1p1", ()),
        "FEM taylor-hood": ("fem-th", ())}
column = {label: soilwater.solve(soilwater.load_case("soil-column", "time.end=40.0", *extra),
                                 method, progress=False)  # the first step only
          for label, (method, extra) in RUNS.items()}
case = column["FEM taylor-hood"].case
load = -case.boundary.top.traction[1]
print(f"h^2 / (c_v dt) = {stability_number(case):.1f}")

profiles = {label: axis_profile(r, 1) for label, r in column.items()}
stability = pd.DataFrame({label: {"overshoot": overshoot(p, load),
                                  "oscillation": oscillation_index(p, load)}
                          for label, (_, p) in profiles.items()}).T
print(stability.to_string(float_format="{:.3f}".format))

# %%
# The two families fail differently. FEM overshoots by about half the load at the
# node below the drained top and is monotone further down. EFG overshoots far less
# (0.1 to 0.25 of the load) but zigzags node to node down the whole column, so its
# oscillation index is the larger one: no weight pair makes EFG stable at this ratio.
# E-A/E-B has the smallest overshoot of the three pairs, in the direction of the
# paper's Table 2, but not the smallest oscillation, so the paper's unqualified "good"
# for E-A/E-B is not reproduced. The report's Table 2 study repeats this at three nodal
# densities and two permeabilities: the oscillation grows with h^2 / (c_v dt) for every
# weight pair, the known limit of equal-order interpolation, and E-A/E-B damps it
# fastest in the later steps.

fig, ax = plt.subplots(figsize=(5, 5), layout="constrained")
for label, (y, p) in profiles.items():
    ax.plot(p / load, y, "o-" if label.startswith("EFG") else "s--", ms=4, label=label)
ax.axvline(1.0, color="k", lw=0.8)
ax.set(xlabel="p_w / load", ylabel="height (m)", title="soil column after 40 s")
ax.legend(fontsize=8)
