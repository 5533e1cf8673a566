r"""
Unconfined compression: EFG cells and quadrature beside FEM
===========================================================

The built-in case ``unconfined-compression`` (paper Fig. 3) is a quarter specimen of
3 x 4 m (111 nodes: a 7 x 9 grid and its 48 cell centres), undrained, on a frictionless
base, with a free side, its top pulled down at D22 = -0.01/s to 20 % strain. The exact
solution is a uniform deformation, so every point follows the driver path of the first
example. Two measures tell how far a solver strays from it:

* the **path error** (:func:`soilwater.studies.harness.metrics.path_error`): the
  largest distance of the run's mean (p', q) from the driver at equal axial strain,
  over p'0;
* **ERR** (paper eq. 1): the mean over the material points of
  \|(D22 - D22^I) / D22\|, how far the points' vertical stretching D22^I is from the
  uniform one (zero for the exact solution).

EFG integrates its weak form on background cells. The paper compares Delaunay
triangles of the current nodes with squares of the initial spacing, which do not
follow the deforming boundary, and finds that only Delaunay cells keep the deformation
uniform. Both are run here with the paper's plain Gauss quadrature (``none``) and with
the variationally consistent correction (``vci``, the default), which restores the
discrete divergence theorem on any cells. Taylor-Hood FEM (``fem-th``, P2/P1 triangles
on the same nodes) is the reference. EFG runs as method ``efg-paper``, the paper's
configuration (state on the nodes, penalty, no pressure stabilisation), the one whose
cells these are. The runs take 50 steps instead of the case's 100 to stay within a
minute.
"""

# %%
import matplotlib.pyplot as plt
import pandas as pd

import soilwater
from soilwater.material.driver import run_test
from soilwater.studies.harness.metrics import path_error

RUNS = {"EFG delaunay none": ("efg-paper", ("efg.cells=delaunay", "efg.correction=none")),
        "EFG delaunay vci": ("efg-paper", ("efg.cells=delaunay", "efg.correction=vci")),
        "EFG squares none": ("efg-paper", ("efg.cells=squares", "efg.correction=none")),
        "EFG squares vci": ("efg-paper", ("efg.cells=squares", "efg.correction=vci")),
        "FEM taylor-hood": ("fem-th", ())}
compression = {
    label: soilwater.solve(soilwater.load_case("unconfined-compression", "time.steps=50",
                                               *extra), method, progress=False)
    for label, (method, extra) in RUNS.items()}

summary = pd.DataFrame(
    {label: {"path_error": path_error(r.history, r.case.material()),
             "err_mean": r.history.err.astype(float).mean(),
             "err_max": r.history.err.astype(float).max()}
     for label, r in compression.items()}).T
print(summary.to_string(float_format="{:.2e}".format))

# %%
# What the numbers say:
#
# * With the correction, Delaunay and square cells give the same path, within about
#   0.01 p'0 of the driver, as FEM does; that error is the time step's (it halves with
#   100 steps).
# * With the paper's plain quadrature, square cells lose the path entirely (an error
#   of several p'0): the cells do not follow the moving boundary, so the quadrature
#   misses or adds parts of the body, and the error feeds back through the material.
#   Delaunay cells keep the path, as the paper says, but not a uniform stretching (ERR
#   of tenths): the paper's ERR near zero on Delaunay cells is reproduced only with
#   the correction.
# * FEM keeps the path but its ERR jumps once the clay is at the critical state
#   (eps_a above about 0.12): there the shear stiffness vanishes, a non-uniform split
#   of the deformation costs no extra stress, and round-off decides which one the
#   solver finds. ERR in that range is fragile (square cells with the correction drift
#   too); only EFG on Delaunay cells with the correction stays uniform to the tolerance.

clay = compression["FEM taylor-hood"].case.material()
driver = run_test(clay, "undrained-plane-strain", 0.2, points=400)
fig, (paths, errs) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
paths.plot(driver.p / clay.p0, driver.q / clay.p0, "k-", lw=2, label="driver")
for label, r in compression.items():
    h = r.history
    paths.plot(h.p / clay.p0, h.q / clay.p0, ".", ms=4, label=label)
    errs.semilogy(h.eps_a, h.err.astype(float), label=label)
paths.set(xlim=(0.4, 1.05), ylim=(0, 0.85), xlabel="p' / p'0", ylabel="q / p'0",
          title="stress path (squares none leaves the frame)")
errs.set(xlabel="axial strain", ylabel="ERR (paper eq. 1)", title="uniformity of D22")
paths.legend(fontsize=8)
