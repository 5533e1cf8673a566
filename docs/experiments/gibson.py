"""The measured numbers of Gibson's finite-strain reference (:mod:`soilwater.references.gibson`).

Quoted by ``docs/studies/gibson.rst``. Prints the small-strain limit against Terzaghi and
the large-strain closed form of Xie and Leo (2004), the convergence table of the 10 m
soft clay column and its finite- against small-strain settlement (Terzaghi with the
initial coefficients at mid-depth).

``python docs/experiments/gibson.py`` (about a minute on one core).
"""

import time

import numpy as np
from scipy.optimize import brentq

from soilwater.references.closed_forms import terzaghi, xie_leo
from soilwater.references.gibson import (Column, consolidation_time, initial_coefficients,
                                         large_strain_column, refinement, solve)
from soilwater.references.gibson_clay import Clay

from common import count, parsed, parser

GAMMA_W = 9.81
FACTORS = np.array([0.01, 0.1, 0.3, 1.0, 3.0])      # t / (d^2 / cv0)


def closed_forms(cells, per_decade):
    """Largest settlement and pore pressure errors against both closed forms; one row
    per check and drainage (``settlement``, ``pressure``: the largest relative errors)."""
    print("check            drainage  max |dS|/S   max |du|/dq  run [s]")
    mv, k, rows = 1e-3, 1e-8, []
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
            result = solve(column, times, cells=cells, steps_per_decade=per_decade)
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
            drainage = "double" if double else "single"
            rows.append({"check": name, "drainage": drainage, "settlement": max(dS),
                         "pressure": max(du), "seconds": run})
            print(f"{name:16s} {drainage:8s}  {max(dS):.2e}     {max(du):.2e}     {run:.2f}")
    return rows


def convergence(column, T, levels, default=(800, 40)):
    """The settlement on each refinement level, the observed order and the
    extrapolation; the relative error of the ``default`` level if it is one of them."""
    times = T * FACTORS
    start = time.perf_counter()
    study = refinement(column, times, levels)
    print(f"\nconvergence, settlement [m] at t/T = {FACTORS.tolist()} "
          f"(T = {T:.4g} s, {time.perf_counter() - start:.0f} s)")
    for (cells, per_decade), row in zip(levels, study["settlement"]):
        values = "  ".join(f"{s:.7f}" for s in row)
        print(f"{cells:5d} cells {per_decade:3d}/decade  {values}")
    print("observed order          " + "  ".join(f"{p:9.2f}" for p in study["order"]))
    print("extrapolated            " + "  ".join(f"{s:.7f}" for s in study["extrapolated"]))
    if tuple(default) in levels:
        at = study["settlement"][levels.index(tuple(default))]
        error = np.abs(at / study["extrapolated"] - 1)
        print(f"default {default[0]}/{default[1]} rel. err "
              + "  ".join(f"{e:9.1e}" for e in error))
    return study


def small_strain(column, T, cells, per_decade):
    """Gibson against Terzaghi with the initial (tangent, mid-depth) coefficients; the
    final settlement [m] and the times to 50 and 90 % of it [T] of each."""
    mv, k, cv = initial_coefficients(column)
    dq = column.load[-1][1] - column.surcharge
    H = column.height
    times = T * np.geomspace(1e-3, 10, 81)
    start = time.perf_counter()
    gibson = solve(column, times, cells=cells, steps_per_decade=per_decade)
    run = time.perf_counter() - start
    final = solve(column, [1e3 * T], cells=cells, steps_per_decade=per_decade).settlement[0]
    small = np.array([terzaghi([0.0], t, dq, H, 1 / mv, 1.0, 0.0, k / GAMMA_W)[1]
                      for t in times])
    print(f"\nfinite vs small strain: mv0 = {mv:.4g} 1/kPa, k0 = {k:.3g} m/s, "
          f"cv0 = {cv:.4g} m2/s, T = H^2/cv0 = {T:.4g} s; Gibson run {run:.2f} s")
    print(f"final settlement: Gibson {final:.4f} m ({final / H:.1%} of H), "
          f"Terzaghi mv0 dq H = {mv * dq * H:.4f} m")
    row = {"final": final, "small_final": mv * dq * H}
    for U in (0.5, 0.9):
        tg = np.exp(np.interp(U, gibson.settlement / final, np.log(times)))
        ts = T * brentq(lambda f: terzaghi([0.0], f * T, dq, H, 1 / mv, 1.0, 0.0,
                                           k / GAMMA_W)[1] / (mv * dq * H) - U, 1e-6, 10)
        row[f"t{int(U * 100)}"] = (tg / T, ts / T)
        print(f"t{int(U * 100)}: Gibson {tg / T:.4f} T, Terzaghi {ts / T:.4f} T")
    for f in FACTORS:
        i = np.argmin(np.abs(times / T - f))
        print(f"t = {times[i] / T:.2f} T: Gibson {gibson.settlement[i]:.4f} m, "
              f"Terzaghi {small[i]:.4f} m ({small[i] / gibson.settlement[i] - 1:+.1%})")
    return row


def main(argv=None):
    """Print the three tables; return ``{"closed_forms": rows, "convergence": study,
    "small_strain": row}``."""
    made = parser(__doc__)
    made.add_argument("--cells", type=count, default=800,
                      help="finite volumes of the closed-form and small-strain runs")
    made.add_argument("--per-decade", type=count, default=40,
                      help="time levels per decade of those runs")
    made.add_argument("--coarsest", nargs=2, type=count, default=[100, 5],
                      metavar=("CELLS", "PER_DECADE"),
                      help="the convergence study's coarsest level, each next one doubled")
    made.add_argument("--levels", type=count, default=5,
                      help="the convergence study's levels (at least 3)")
    with parsed(made, argv) as args:
        if args.levels < 3:
            made.error("--levels: the observed order needs at least 3 levels")
        cells, per_decade = args.coarsest
        levels = [(cells * 2**i, per_decade * 2**i) for i in range(args.levels)]
        column = large_strain_column()
        T = consolidation_time(column)
        return {"closed_forms": closed_forms(args.cells, args.per_decade),
                "convergence": convergence(column, T, levels),
                "small_strain": small_strain(column, T, args.cells, args.per_decade)}


if __name__ == "__main__":
    main()
