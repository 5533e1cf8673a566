"""Finite-strain consolidation under self-weight: the built-in ``large-strain-column`` (a
geostatic soft clay layer loaded tenfold) and ``self-weight-consolidation`` (a freshly
deposited layer), each method against Gibson's finite-strain reference
(:mod:`soilwater.references.gibson`, which shares no code with the solvers), and the loaded
column against small-strain Terzaghi with the initial coefficients at mid-depth.

The reference column is the case's: the compression line is the case's normally
consolidated one-dimensional line (:func:`soilwater.physics.geostatic.normal_void_ratio`,
slopes lambda and kappa in ``e``-``ln sigma'_v``, which the modified Cam-clay follows
exactly along its K0 path), the same permeability law, unit weights, height, surcharge,
load and drainage. Time is measured in ``T = d^2 / c_v0``
(:func:`soilwater.references.gibson.consolidation_time`).
"""

import numpy as np
import pandas as pd

from soilwater.studies.harness import tables
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.runs import solved
from soilwater.references import gibson, gibson_clay
from soilwater.references.closed_forms import terzaghi
from soilwater.physics.geostatic import G_N, initial_state, normal_void_ratio
from soilwater.case.loader import load_case

#: The methods: EFG recommended, the two FEM pairs, and EFG in the paper's configuration
#: (its nodal state is what the consistent schemes replace).
METHODS = ("efg", "fem-th", "fem-p1p1-stab", "efg-paper")
CASES = ("large-strain-column", "self-weight-consolidation")
#: Lower ends of the time windows of the settlement errors, in T.
WINDOWS = (0.01, 0.1, 1.0)
#: Times of the profiles, in T.
PROFILE_TIMES = (0.05, 0.3, 1.0)
#: Gibson's resolution: cells and steps per decade (converged to about 1e-4,
#: soilwater.references.gibson).
RESOLUTION = pick((800, 40), (200, 20))
#: The anchor stress of the reference's compression line [kPa] (any: the line is one).
SIGMA_REF = 10.0


def column(case):
    """The :class:`soilwater.references.gibson.Column` of a case (module docstring)."""
    material, fluid = case.material(), case.fluid
    assert case.gravity.g in (0.0, G_N), "Gibson's column weighs at standard gravity"
    clay = gibson_clay.Clay(lam=material.lam, kappa=material.kappa, sigma_v_ref=SIGMA_REF,
                       e_ref=float(normal_void_ratio(material, SIGMA_REF)),
                       permeability=fluid.permeability,
                       permeability_law=fluid.permeability_law,
                       permeability_e=fluid.permeability_e,
                       permeability_ck=fluid.permeability_ck,
                       specific_gravity=fluid.specific_gravity, gamma_w=fluid.gamma_w)
    edges = dict(case.boundary.items())
    surcharge, extra = case.initial.surcharge, -float(edges["top"].traction[1])
    load = case.loading.load
    table = ((0.0, load),) if isinstance(load, float) else load
    deposited = case.initial.stress == "uniform"
    return gibson.Column(clay, height=case.geometry.height, surcharge=surcharge,
                         load=tuple((t, surcharge + extra * f) for t, f in table)
                         if extra else (),
                         start="deposited" if deposited else "geostatic",
                         ocr=case.initial.ocr,
                         e_deposited=material.e0 if deposited else None,
                         self_weight=case.gravity.g > 0,
                         drained_bottom=edges["bottom"].drained)


def static_settlement(case):
    """The settlement [m] at the end of consolidation by quadrature, from the case's own
    start: its solids (per unit area), and in the end every depth on the normally
    consolidated line (:func:`soilwater.physics.geostatic.normal_void_ratio`) at the top's effective
    stress plus the buoyant weight of the solids above. The top's stress is the
    surcharge plus the load for a geostatic start, and p'0 plus the load for a uniform
    one (its initial stress held as a surcharge)."""
    material, fluid = case.material(), case.fluid
    H = case.geometry.height
    y = np.linspace(0.0, H, 20001)
    _, state = initial_state(case, material, np.column_stack([0 * y, y]))
    Z = np.trapezoid(1 / state["v"], y)
    extra = -float(dict(case.boundary.items())["top"].traction[1])
    start = case.initial.surcharge if case.initial.stress == "geostatic" else material.p0
    top = start + extra * float(case.loading.factor(case.time.end))
    z = np.linspace(0.0, Z, 20001)
    weight = (fluid.specific_gravity - 1) * fluid.gamma_w * case.gravity.g / G_N
    return float(H - np.trapezoid(1 + normal_void_ratio(material, top + weight * (Z - z)),
                                  z))


def _runs():
    """``(case name, method, Result)`` of every run."""
    specs = [(name, (), method) for name in CASES for method in METHODS]
    return [(s[0], s[2], r) for s, r in zip(specs, solved(specs))]


def curves():
    """Settlement against time per case and method, with Gibson's at the same times.

    Returns
    -------
    pandas.DataFrame
        ``case, method, time`` [s], ``t_over_T``, ``settlement`` and ``gibson`` [m],
        ``error`` (relative to Gibson), ``iterations`` and per run ``run_time`` [s].
    """
    frames = []
    for name, method, result in _runs():
        case = load_case(name)
        ref = column(case)
        h = result.history
        t = h["time"].to_numpy()
        g = gibson.solve(ref, t, *RESOLUTION).settlement
        s = h["settlement"].to_numpy()
        frames.append(pd.DataFrame({
            "case": name, "method": method, "time": t,
            "t_over_T": t / gibson.consolidation_time(ref), "settlement": s, "gibson": g,
            "error": s / g - 1, "iterations": h["iterations"].to_numpy(),
            "run_time": result.summary["timings"]["total_s"]}))
    return pd.concat(frames, ignore_index=True)


def small_strain(table):
    """Terzaghi's settlement of the loaded column with its initial coefficients at
    mid-depth (``mv``, ``c_v``), the load stepped at t = 0+, at the times of
    :func:`curves`.

    Returns
    -------
    pandas.DataFrame
        ``time`` [s], ``t_over_T``, ``settlement`` [m], ``gibson`` [m].
    """
    case = load_case(CASES[0])
    ref = column(case)
    mv, k, _ = gibson.initial_coefficients(ref)
    load = ref.load[-1][1] - ref.surcharge
    rows = table[(table.case == CASES[0]) & (table.method == METHODS[1])]
    t = rows.time.to_numpy()
    s = [terzaghi(0.0, ti, load, ref.height, 1 / mv, 1.0, 0.0, k / ref.clay.gamma_w)[1]
         for ti in t]
    return pd.DataFrame({"time": t, "t_over_T": rows.t_over_T.to_numpy(),
                         "settlement": s, "gibson": rows.gibson.to_numpy()})


def summary(table):
    """Per case and method: the largest settlement error against Gibson from each of
    :data:`WINDOWS` on, the final settlement and its error, steps, run time.

    Returns
    -------
    pandas.DataFrame
        ``case, method``, ``error_from_<w>T`` per window, ``final`` [m],
        ``final_gibson`` [m], ``final_error``, ``final_static`` (:func:`static_settlement`
        of the case) [m] and ``final_static_error``, ``steps``, ``iterations_per_step``,
        ``run_time`` [s].
    """
    rows = []
    for (name, method), run in table.groupby(["case", "method"], sort=False):
        row = {"case": name, "method": method}
        for w in WINDOWS:
            inside = run[run.t_over_T >= w]
            row[f"error_from_{w:g}T"] = float(np.abs(inside.error).max())
        last = run.iloc[-1]
        static = static_settlement(load_case(name))
        row.update(final=last.settlement, final_gibson=last.gibson,
                   final_error=last.error, final_static=static,
                   final_static_error=last.settlement / static - 1, steps=len(run),
                   iterations_per_step=run.iterations.mean(), run_time=last.run_time)
        rows.append(row)
    return pd.DataFrame(rows)


def profiles():
    """Profiles along the centre line at :data:`PROFILE_TIMES` (the nearest output
    time), per case and method, with Gibson's at the same current heights.

    Returns
    -------
    pandas.DataFrame
        ``case, method, t_over_T, height`` (current, above the base) [m], ``e``,
        ``e_gibson``, ``p_w``, ``p_w_gibson`` (excess) [kPa], ``k``, ``k_gibson``
        [m/s], ``p_eff`` [kPa] and ``p_eff_gibson`` (Gibson's sigma'_v times ``(1 + 2
        K0) / 3``, K0 the material's normally consolidated value) [kPa].
    """
    frames = []
    for name, method, result in _runs():
        case = load_case(name)
        ref = column(case)
        T = gibson.consolidation_time(ref)
        times = np.array([s.time for s in result.snapshots])
        picked = [result.snapshots[int(np.abs(times - f * T).argmin())]
                  for f in PROFILE_TIMES]
        g = gibson.solve(ref, [s.time for s in picked], *RESOLUTION)
        k0 = case.material().k0_nc()
        for i, snap in enumerate(picked):
            data = snap.point_data
            x0 = snap.points - data["u"]
            line = np.flatnonzero(np.isclose(x0[:, 0], case.geometry.width / 2))
            line = line[np.argsort(snap.points[line, 1])]
            y = snap.points[line, 1]

            def at(values):
                return np.interp(y, g.xi[i], values[i])
            frames.append(pd.DataFrame({
                "case": name, "method": method, "t_over_T": snap.time / T, "height": y,
                "e": data["v"][line] - 1, "e_gibson": at(g.e),
                "p_w": data["p_w"][line], "p_w_gibson": at(g.u_e),
                "k": data["permeability"][line], "k_gibson": at(g.k),
                "p_eff": data["p_eff"][line],
                "p_eff_gibson": at(g.sigma_eff) * (1 + 2 * k0) / 3}))
    return pd.concat(frames, ignore_index=True)


def profile_summary(table):
    """Per case and method: the largest profile errors over :data:`PROFILE_TIMES`:
    ``p_w`` against Gibson's over ``excess_scale``, the largest excess pore pressure of
    the case's reference (:func:`_excess_scale`), ``e`` (absolute), ``k`` and ``p_eff``
    (relative)."""
    rows = []
    for (name, method), run in table.groupby(["case", "method"], sort=False):
        scale = _excess_scale(column(load_case(name)))
        rows.append({"case": name, "method": method,
                     "p_w_error": float(np.abs(run.p_w - run.p_w_gibson).max() / scale),
                     "e_error": float(np.abs(run.e - run.e_gibson).max()),
                     "k_error": float(np.abs(run.k / run.k_gibson - 1).max()),
                     "p_eff_error": float(np.abs(run.p_eff / run.p_eff_gibson - 1).max()),
                     "excess_scale": scale})
    return pd.DataFrame(rows)


def _top_stress(case):
    """The effective stress [kPa] at the top of Gibson's deposited column: its
    compression line's at the deposit's void ratio."""
    ref = column(case)
    return float(ref.clay.virgin_stress(ref.e_deposited))


def _excess_scale(ref):
    """The largest excess pore pressure of a reference column [kPa]: its load change, or
    for an unloaded one the weight of the deposit that the water carries at t = 0+."""
    if ref.load:
        return abs(ref.load[-1][1] - ref.surcharge)
    return float(np.abs(gibson.solve(ref, [1e-9 * gibson.consolidation_time(ref)],
                                     *RESOLUTION).u_e).max())


def section(summary, small, profile_errors):
    """The report's lines on finite-strain consolidation."""
    loaded = summary[summary.case == CASES[0]].set_index("method")
    deposited = summary[summary.case == CASES[1]].set_index("method")
    errs = profile_errors.set_index(["case", "method"])
    w = f"error_from_{WINDOWS[1]:g}T"
    final_small = small.settlement.iloc[-1]
    final_gibson = small.gibson.iloc[-1]
    return [
        "",
        "## Finite-strain consolidation under self-weight",
        "",
        "![large strain](figures/large_strain.png)",
        "",
        f"`{CASES[0]}`: a 10 m normally consolidated soft clay layer (modified Cam-clay, "
        "lambda = 0.4, kappa = 0.04, Taylor permeability) starts geostatically under its "
        "buoyant weight and 20 kPa, is loaded to 200 kPa and drains through its top. "
        f"`{CASES[1]}`: the same clay deposited at e = 3.0 consolidates under its own "
        "weight. Reference: Gibson's finite-strain equation (`soilwater.references.gibson`, an "
        "independent finite-volume solver converged to about 1e-4 in settlement) on the "
        "case's compression line and permeability law. Gibson's loaded column settles "
        f"{final_gibson:.3f} m ({final_gibson / 10 * 100:.0f} % of its height); "
        f"small-strain Terzaghi with the initial coefficients at mid-depth says "
        f"{final_small:.3f} m, {final_small / final_gibson:.2f} times as much: "
        "small-strain theory is useless at this load ratio.",
        "",
        tables.to_markdown(summary, floatfmt="{:.4g}"),
        "",
        f"Against the targets on `{CASES[0]}` (settlement within 2 % from 0.1 T "
        "on, final within 1 %, pore pressure profiles within 2 % of the load): "
        + "; ".join(f"{m} {loaded.loc[m, w] * 100:.2f} % / "
                    f"{abs(loaded.loc[m, 'final_error']) * 100:.2f} % / "
                    f"{errs.loc[(CASES[0], m), 'p_w_error'] * 100:.2f} %"
                    for m in METHODS)
        + f". On `{CASES[1]}`: "
        + "; ".join(f"{m} {deposited.loc[m, w] * 100:.2f} % / "
                    f"{abs(deposited.loc[m, 'final_error']) * 100:.2f} % / "
                    f"{errs.loc[(CASES[1], m), 'p_w_error'] * 100:.2f} %"
                    for m in METHODS)
        + ". Gibson's deposit starts on the one-dimensional compression line at e = 3.0, "
        f"where it carries {_top_stress(load_case(CASES[1])):.2f} kPa; the case starts "
        "isotropically at p'0 = 2 kPa, which it keeps on its top as a surcharge. That "
        "alone moves the end of consolidation: by quadrature (`final_static`) the case's "
        f"own start ends at {deposited.final_static.iloc[0]:.4f} m, Gibson's at "
        f"{deposited.final_gibson.iloc[0]:.4f} m, and the methods end within "
        + ", ".join(f"{m} {abs(deposited.loc[m, 'final_static_error']) * 100:.2f} %"
                    for m in METHODS)
        + " of their own start's static state. Before the end the three methods' "
        f"largest errors from 0.1 T on lie between {deposited[w].min() * 100:.2f} and "
        f"{deposited[w].max() * 100:.2f} %, close to one another: how much of that "
        "earlier difference is also the starts' is not separated here.",
        "",
        "![profiles](figures/large_strain_profiles.png)",
        "",
        "Profile errors at t = " + ", ".join(f"{f:g}" for f in PROFILE_TIMES)
        + " T (excess pore pressure over the largest excess of the reference, void ratio "
        "absolute, permeability and p' relative):",
        "",
        tables.to_markdown(profile_errors, floatfmt="{:.3g}"),
    ]

