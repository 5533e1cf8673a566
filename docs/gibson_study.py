"""The measured numbers of the Gibson reference (soilwater.references.gibson), README "Gibson's
finite-strain reference": python docs/gibson_study.py (about a minute on one core).

Prints the small-strain limit against Terzaghi, the large-strain closed form of Xie and
Leo (2004), the convergence table of the 10 m soft clay column and its finite- against
small-strain settlement (Terzaghi with the initial coefficients at mid-depth).
"""

import time

import numpy as np
from scipy.optimize import brentq

from soilwater.references.closed_forms import terzaghi, xie_leo
from soilwater.references.gibson import (Column, consolidation_time, initial_coefficients,
                                         large_strain_column, refinement, solve)
from soilwater.references.gibson_clay import Clay

GAMMA_W = 9.81
FACTORS = np.array([0.01, 0.1, 0.3, 1.0, 3.0])      # t / (d^2 / cv0)


def closed_forms():
    """Largest settlement and pore pressure errors against both closed forms."""
    print("check            drainage  max |dS|/S   max |du|/dq  run [s]")
    mv, k = 1e-3, 1e-8
    for name, H, dq, e0, law in (("terzaghi", 1.0, 0.01, 1.0, "constant"),
                                 ("xie-leo", 10.0, 300.0, 1.5, "xie-leo")):
        clay = Clay(compression="constant-mv", mv=mv, e_ref=e0, sigma_v_ref=50.0,
                    permeability=k, permeability_law=law)
        for double in (False, True):
            column = Column(clay, height=H, surcharge=50.0, load=((0.0, 50.0 + dq),),
                            self_weight=False, drained_bottom=double)
            path = H / 2 if double else H
            times = path**2 * GAMMA_W * mv / k * FACTORS
            start = time.perf_counter()
            result = solve(column, times)
            run = time.perf_counter() - start
            dS, du = [], []
            for i, t in enumerate(times):
                if name == "terzaghi":
                    height = np.abs(result.xi[i] - H / 2) if double else result.xi[i]
                    u, s = terzaghi(height, t, dq, path, 1 / mv, 1.0, 0.0, k / GAMMA_W)
                    s *= H / path
                else:
                    depth = (result.solid_height - result.z) * (1 + e0)
                    u, s = xie_leo(depth, t, dq, H, mv, k, GAMMA_W, double)
                dS.append(abs(result.settlement[i] / s - 1))
                du.append(np.abs(result.u_e[i] - u).max() / dq)
            print(f"{name:16s} {'double' if double else 'single':8s}  {max(dS):.2e}"
                  f"     {max(du):.2e}     {run:.2f}")


def convergence(column, T):
    times = T * FACTORS
    levels = ((100, 5), (200, 10), (400, 20), (800, 40), (1600, 80))
    start = time.perf_counter()
    study = refinement(column, times, levels)
    print(f"\nconvergence, settlement [m] at t/T = {FACTORS.tolist()} "
          f"(T = {T:.4g} s, {time.perf_counter() - start:.0f} s)")
    for (cells, per_decade), row in zip(levels, study["settlement"]):
        values = "  ".join(f"{s:.7f}" for s in row)
        print(f"{cells:5d} cells {per_decade:3d}/decade  {values}")
    print("observed order          " + "  ".join(f"{p:9.2f}" for p in study["order"]))
    print("extrapolated            " + "  ".join(f"{s:.7f}" for s in study["extrapolated"]))
    default = study["settlement"][3]
    error = np.abs(default / study["extrapolated"] - 1)
    print("default 800/40 rel. err " + "  ".join(f"{e:9.1e}" for e in error))


def small_strain(column, T):
    """Gibson against Terzaghi with the initial (tangent, mid-depth) coefficients."""
    mv, k, cv = initial_coefficients(column)
    dq = column.load[-1][1] - column.surcharge
    H = column.height
    times = T * np.geomspace(1e-3, 10, 81)
    start = time.perf_counter()
    gibson = solve(column, times)
    run = time.perf_counter() - start
    final = solve(column, [1e3 * T]).settlement[0]
    small = np.array([terzaghi([0.0], t, dq, H, 1 / mv, 1.0, 0.0, k / GAMMA_W)[1]
                      for t in times])
    print(f"\nfinite vs small strain: mv0 = {mv:.4g} 1/kPa, k0 = {k:.3g} m/s, "
          f"cv0 = {cv:.4g} m2/s, T = H^2/cv0 = {T:.4g} s; Gibson run {run:.2f} s")
    print(f"final settlement: Gibson {final:.4f} m ({final / H:.1%} of H), "
          f"Terzaghi mv0 dq H = {mv * dq * H:.4f} m")
    for U in (0.5, 0.9):
        tg = np.exp(np.interp(U, gibson.settlement / final, np.log(times)))
        ts = T * brentq(lambda f: terzaghi([0.0], f * T, dq, H, 1 / mv, 1.0, 0.0,
                                           k / GAMMA_W)[1] / (mv * dq * H) - U, 1e-6, 10)
        print(f"t{int(U * 100)}: Gibson {tg / T:.4f} T, Terzaghi {ts / T:.4f} T")
    for f in (0.01, 0.1, 0.3, 1.0, 3.0):
        i = np.argmin(np.abs(times / T - f))
        print(f"t = {times[i] / T:.2f} T: Gibson {gibson.settlement[i]:.4f} m, "
              f"Terzaghi {small[i]:.4f} m ({small[i] / gibson.settlement[i] - 1:+.1%})")


if __name__ == "__main__":
    closed_forms()
    column = large_strain_column()
    T = consolidation_time(column)
    convergence(column, T)
    small_strain(column, T)
