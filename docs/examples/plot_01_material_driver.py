r"""
The material alone: Table 1 Cam-clay on its undrained path
==========================================================

The preset ``table1`` is the clay of the seed paper (*Applicability of the meshless
method to soil-water coupled problems*): original Cam-clay with lambda = 0.11,
kappa = 0.04, M = 1.42, nu = 0.333, e0 = 0.83, normally consolidated at p'0 = 3 kPa.

Undrained plane-strain compression (D_yy = -D_xx, D_zz = 0) keeps the volume, so the
plastic volumetric strain is minus the elastic one. With K = v p'/kappa that gives the
path in closed form,

.. math:: \frac{q}{M p'} = \frac{\ln(p'_0 / p')}{\Lambda}, \qquad
          \Lambda = \frac{\lambda - \kappa}{\lambda},

which ends at the critical state p'_f = p'0 exp(-Lambda), q_f = M p'_f.

:func:`soilwater.material.driver.run_test` integrates the rate equations of the
material with an adaptive Runge-Kutta method and no return mapping: it is the paper's
"theoretical solution" and the reference of the examples that follow. Here it is
checked against the closed form.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from soilwater.material.driver import closed_form_q, run_test
from soilwater.material.presets import load_material

clay = load_material("table1")
driver = run_test(clay, "undrained-plane-strain", 0.2, points=400)
gap = np.abs(driver.q - closed_form_q(clay, driver.p)).max() / clay.p0
p_f = clay.p0 * np.exp(-clay.Lambda)
print(f"driver vs closed form: max |q - q_closed| / p'0 = {gap:.1e}")
print(f"at eps_a = 0.2: p'/p'0 = {driver.p.iloc[-1] / clay.p0:.4f}, "
      f"q/p'0 = {driver.q.iloc[-1] / clay.p0:.4f}; critical state: "
      f"{p_f / clay.p0:.4f}, {clay.M * p_f / clay.p0:.4f}")

# %%
# The driver agrees with the closed form to its integration tolerance, and at 20 %
# strain the clay sits at the critical state: from there on it shears with no change
# of stress.

fig, (path, curve) = plt.subplots(1, 2, figsize=(9, 4), layout="constrained")
path.plot(driver.p / clay.p0, driver.q / clay.p0, "k-", lw=2, label="driver")
path.plot(driver.p / clay.p0, closed_form_q(clay, driver.p) / clay.p0, "r--",
          label="closed form")
path.plot([0, 1], [0, clay.M], "k:", lw=0.8, label="critical state line")
path.set(xlim=(0.4, 1.05), ylim=(0, 0.85), xlabel="p' / p'0", ylabel="q / p'0",
         title="undrained stress path")
path.legend(fontsize=8)
curve.plot(driver.eps_a, driver.q / clay.p0, "k-")
curve.set(xlabel="axial strain", ylabel="q / p'0", title="stress-strain curve")
