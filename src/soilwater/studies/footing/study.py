"""The strip-footing study: how far each method pushes a rigid footing into undrained
clay, how close it comes to Prandtl's limit pressure ``(2 + pi) s_u``, how it converges
and at what cost.

The built-in ``strip-footing`` case (footing width B = 1 m, symmetry half, weightless
normally consolidated Cam-clay, k = 0, 10 B x 10 B) is run by each method of
:data:`METHODS` on the three node densities of :data:`DENSITIES` (the built-in layout
refined, :func:`soilwater.studies.harness.grids.refined`) to a settlement of 0.5 B, and the
paper's EFG configuration also with more time steps on the coarsest nodes
(:data:`EFG_STEPS`), the evidence that its pressure depends on the step count. ``s_u`` is the clay's
plane-strain undrained strength
(:func:`soilwater.references.closed_forms.undrained_strength`). The reference curve is
that of :data:`REFERENCE`, the finest Taylor-Hood run; a run's error is its largest
relative distance from it. The node set distorts as a mesh would: each triangle of the
initial nodes (FEM: its elements; EFG: the Delaunay triangles of its initial nodes moved
with them, which ``efg`` integrates on until it rebuilds them and ``efg-paper`` does not,
since it re-triangulates every step) is distorted once its
smallest angle falls below :data:`soilwater.geometry.quality.DISTORTED` of its undeformed value.
"""

import numpy as np
import pandas as pd

from soilwater.studies.harness import deformation
from soilwater.studies.harness import tables
from soilwater.studies.harness.footing import CASE, METHODS, time_steps, width
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.runs import solved
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.case.loader import load_case
from soilwater.geometry.quality import DISTORTED
from soilwater.methods import EFG_METHODS

#: Equal spacings per B at the footing (:func:`soilwater.studies.harness.grids.refined`);
#: the middle one is the built-in case's.
DENSITIES = pick((4, 8, 12), (2, 4))
#: Time steps to 0.5 B of the extra runs of :data:`STEPPED` on the coarsest nodes (the
#: case has 100; a quick report 50).
EFG_STEPS = pick((200, 400), (100, 200))
#: The method whose step-count dependence the extra runs show: the paper's scheme.
STEPPED = "efg-paper"
#: Settlement [B] to which every method is pushed on the built-in nodes (at the built-in
#: step), to see how far it gets.
DEEP = pick(1.0, 0.75)
#: The run whose curve the others are measured against: (label, density).
REFERENCE = ("fem-th", DENSITIES[-1])
#: A curve is "within" Prandtl's pressure from the first settlement where it is within
#: this fraction of it.
WITHIN = 0.05
#: Settlement [B] at which each curve's pressure is compared with Prandtl's.
AT = 0.1
#: Errors against the reference are taken from this settlement [B] on (below it the
#: pressures are small and their relative differences large).
FROM = 0.05


def family(labels):
    """The :data:`METHODS` label each run label belongs to (``"efg, 200 steps"`` and
    ``"efg, to 1 B"`` to ``"efg"``)."""
    return labels.str.split(",").str[0]


def meshless(labels):
    """Whether each run label is an EFG run (any :data:`METHODS` entry solved by EFG)."""
    return family(labels).map(lambda f: METHODS[f][0] in EFG_METHODS)


def runs(methods=METHODS, densities=DENSITIES, efg_steps=EFG_STEPS, deep=DEEP):
    """The study's runs: ``(label, method, density, steps, overrides)``: every method on
    every density to the case's 0.5 B, EFG with more steps on the coarsest nodes, and
    every method on the middle density (the built-in nodes) to ``deep`` B (label
    ``"METHOD, to 1 B"``; steps counted to 0.5 B). Steps: the case's, or half as many in
    a quick report (:func:`~soilwater.studies.harness.footing.time_steps`)."""
    case = load_case(CASE)
    steps, end = time_steps(case), case.time.end
    middle = densities[len(densities) // 2]
    out = [(label, method, core, steps, (*refined(core), *extra, f"time.steps={steps}"))
           for label, (method, extra) in methods.items() for core in densities]
    out += [(f"{STEPPED}, {n} steps", STEPPED, densities[0], n,
             (*refined(densities[0]), f"time.steps={n}")) for n in efg_steps]
    factor = deep / 0.5
    return out + [(f"{label}, to {deep:g} B", method, middle, steps,
                   (*refined(middle), *extra, f"time.end={end * factor!r}",
                    f"time.steps={round(steps * factor)}"))
                  for label, (method, extra) in methods.items()]


def curves(study=None):
    """Load-settlement curves and per-level diagnostics of every run of :func:`runs`.

    Returns
    -------
    pandas.DataFrame
        One row per time level: ``label, method, core`` (spacings per B at the footing),
        ``nodes`` (nx x ny), ``steps`` (to 0.5 B), ``to`` (the run's last settlement over
        B, if it gets there), ``settlement`` (over B), ``pressure``
        (mean contact pressure over ``(2 + pi) s_u``), ``min_angle`` [degrees] and
        ``min_quality`` of the worst cell (FEM elements, EFG background cells),
        ``distortion`` (the smallest ratio of a triangle's smallest angle to its
        undeformed one, :func:`distortion`), ``min_rcond`` (EFG's support-coverage check:
        the smallest reciprocal condition number of its MLS moment matrices; NaN for
        FEM), ``iterations``, ``substeps``, and per run
        ``run_time`` [s] and ``reached`` (the last converged settlement over B; a run
        that stops early is kept up to its last converged level).
    """
    study = runs() if study is None else study
    case = load_case(CASE)
    B, s_u = width(case), undrained_strength(case.material())
    frames = []
    for (label, method, core, steps, overrides), result in zip(
            study, solved([(CASE, o, m) for _, m, _, _, o in study])):
        h, d = result.history, result.case.discretisation
        frames.append(pd.DataFrame({
            "label": label, "method": method, "core": core, "nodes": f"{d.nx}x{d.ny}",
            "steps": steps, "to": _end(result.case) / B,
            "settlement": h["settlement@footing"].to_numpy() / B,
            "pressure": h["pressure@footing"].to_numpy() / (PRANDTL * s_u),
            "min_angle": h["min_angle"].to_numpy(), "min_quality": h["min_quality"].to_numpy(),
            "distortion": distortion(result)[1:],
            "min_rcond": h["min_rcond"].to_numpy() if "min_rcond" in h else np.nan,
            "iterations": h["iterations"].to_numpy(), "substeps": h["substeps"].to_numpy(),
            "run_time": result.summary["timings"]["total_s"],
            "reached": h["settlement@footing"].iloc[-1] / B}))
    return pd.concat(frames, ignore_index=True)


def _end(case):
    """The footing's settlement at the case's end [m]."""
    (_, footing), = case.boundary.segments()
    return footing.settlement_rate * case.time.end


def distortion(result):
    """The smallest ratio of a triangle's smallest angle to its undeformed value, per
    snapshot, over the triangles of :func:`soilwater.studies.harness.deformation.triangulation`
    (negative once one has inverted)."""
    triangles = deformation.triangulation(result.snapshots[0])
    angles = deformation.smallest_angles(result.snapshots, triangles)
    return (angles / angles[0]).min(axis=1)


def summary(table, within=WITHIN, at=AT, reference=REFERENCE):
    """Per run: how far it got, where it comes within ``within`` of Prandtl's pressure,
    its pressure at ``at`` B and at 0.5 B, its error against the reference run, when its
    cells become slivers, and its cost.

    Returns
    -------
    pandas.DataFrame
        ``label, nodes, steps, to, reached`` (B), ``within_at`` (the first settlement over B
        within ``within`` of ``(2 + pi) s_u``; NaN if never), ``at_0.1B``, ``at_0.5B``
        (pressure over ``(2 + pi) s_u``; NaN if not reached), ``error`` (the largest
        ``|p / p_ref - 1|`` from :data:`FROM` to the settlement both reached),
        ``min_angle`` [degrees] (the worst cell over the run: FEM elements, EFG
        background cells), ``min_rcond`` (EFG, the smallest over the run),
        ``distortion`` (the smallest at the end), ``distorted_at``
        (the first settlement over B with a triangle below :data:`DISTORTED` of its
        undeformed smallest angle; NaN if none),
        ``run_time`` [s], ``iterations_per_step``, ``cutbacks`` (levels that needed a
        smaller step).
    """
    ref = table[(table.label == reference[0]) & (table.core == reference[1])]
    rows = []
    for (label, core), run in table.groupby(["label", "core"], sort=False):
        s, p = run.settlement.to_numpy(), run.pressure.to_numpy()
        close = np.flatnonzero(np.abs(p - 1) <= within)
        distorted = np.flatnonzero(run.distortion.to_numpy() < DISTORTED)
        error = _error(s, p, ref, ref.settlement.max())
        rows.append({"label": label, "nodes": run.nodes.iloc[0], "steps": run.steps.iloc[0],
                     "to": run.to.iloc[0], "reached": run.reached.iloc[0],
                     "within_at": s[close[0]] if close.size else np.nan,
                     f"at_{at:g}B": _at(s, p, at), "at_0.5B": _at(s, p, 0.5),
                     "error": error, "min_angle": run.min_angle.min(),
                     "min_rcond": run.min_rcond.min(),
                     "distortion": run.distortion.iloc[-1],
                     "distorted_at": s[distorted[0]] if distorted.size else np.nan,
                     "run_time": run.run_time.iloc[0],
                     "iterations_per_step": run.iterations.sum() / len(run),
                     "cutbacks": int((run.substeps > 1).sum())})
    return pd.DataFrame(rows)


def _error(s, p, ref, upto):
    """The largest ``|p / p_ref - 1|`` of a curve (settlement s, pressure p) against the
    reference curve ``ref`` from :data:`FROM` to ``upto`` B (0 if none)."""
    both = (s >= FROM) & (s <= upto + 1e-12)
    return float(np.abs(p[both] / np.interp(s[both], ref.settlement, ref.pressure)
                        - 1).max(initial=0.0))


def _at(s, p, where):
    """Pressure at settlement ``where``, NaN beyond the run's reach."""
    return float(np.interp(where, s, p)) if s[-1] >= where - 1e-9 else np.nan


def section(summary):
    """The report's strip-footing section from :func:`summary`'s table."""
    at = f"at_{AT:g}B"
    base = summary[summary.label.isin(list(METHODS))]
    by = base.set_index(["label", "nodes"])
    efg = summary[(family(summary.label) == STEPPED) & (summary.to == summary.to.min())]
    deep = summary[summary.to > summary.to.min()]
    coarse = efg[efg.nodes == efg.nodes.iloc[0]].sort_values("steps")
    stops = summary[summary.reached < summary.to - 1e-9]
    distorted = summary[summary.distorted_at.notna()]
    return [
        "## Strip footing: how far each method gets",
        "",
        "![footing](figures/footing.png)",
        "",
        "![footing convergence](figures/footing_convergence.png)",
        "",
        "A rigid smooth strip footing (B = 1 m, symmetry half) pushed at a constant rate "
        "into a weightless normally consolidated Cam-clay layer (Table 1, p'0 = 3 kPa, "
        "undrained, total stress zero at the start), 10 B wide and 10 B deep, to a "
        "settlement of 0.5 B in 100 steps (`soilwater run strip-footing --method "
        "METHOD`; `efg` is EFG's recommended configuration, material state at the Gauss "
        "points of Lagrangian cells, Nitsche's essential conditions and the pressure "
        "perturbation; `efg-paper` the paper's, state on the nodes, penalty, no "
        "stabilisation; `fem-th+remesh` is fem-th "
        "with `--set fem.remesh=delaunay`), and on "
        f"the built-in nodes to {DEEP:g} B at the same step. Nodes: equal spacings of B/n "
        "within B of the footing, growing to 4 "
        "times that at the far edges; n = " + ", ".join(map(str, DENSITIES))
        + " (the built-in case has 8). Pressures are the mean contact pressure over "
        "Prandtl's (2 + pi) s_u, s_u = M p'_f / sqrt(3) with p'_f = p'0 exp(-Lambda), "
        "the clay's plane-strain undrained strength "
        f"({undrained_strength(load_case(CASE).material()):.4g} kPa). `within_at` is the "
        f"first settlement (over B) within {WITHIN:.0%} of it; `error` the largest "
        f"relative distance from the reference curve ({REFERENCE[0]}, "
        f"{by.loc[REFERENCE[0]].index[-1]} nodes) from {FROM:g} B on, up to where the run "
        "stops if it stops earlier (a shorter range than the others'); `min_angle` the "
        "smallest angle of any cell over the run, negative once a cell has inverted "
        "(FEM: its elements; EFG: its background "
        "triangles, rebuilt every step; the grid's far cells, 4 times longer than wide, "
        "start at 14 degrees); `min_rcond` EFG's support-coverage check, the smallest "
        "reciprocal condition number of its MLS moment matrices over the run (the solver "
        "stops below 1e-10); `distortion` the smallest ratio, at the end, of a "
        "triangle's smallest angle to its undeformed one, negative once one has inverted "
        "(FEM: its elements; EFG: the "
        "Delaunay triangles of its initial nodes, moved with them, which it does not use) "
        f"and `distorted_at` the first settlement where it falls below {DISTORTED:.2g}; "
        "a run that fails stops at its last converged level (`reached`).",
        "",
        tables.to_markdown(summary, floatfmt="{:.3g}"),
        "",
        f"At {AT:g} B the pressure over (2 + pi) s_u is, from the coarsest to the finest "
        "nodes: " + "; ".join(
            f"{label} " + ", ".join(f"{v:.3g}" for v in group[at])
            for label, group in base.groupby("label", sort=False)) + f". {STEPPED} on the "
        "coarsest nodes with " + ", ".join(map(str, coarse.steps)) + " steps: "
        + ", ".join(f"{v:.3g}" for v in coarse[at])
        + " (by `tests/test_footing.py`, not this run: on 11 x 11 nodes fem-th's pressure "
        "at 0.1 B moves by 0.2 % when its step is halved). "
        + f"To {DEEP:g} B on the built-in nodes: " + ", ".join(
            f"{r.label.split(',')[0]} reached {r.reached:.3g} B" for r in deep.itertuples())
        + ". " + ("Every run reaches its end." if stops.empty else "Runs that stop early: "
           + "; ".join(f"{r.label} on {r.nodes} nodes at {r.reached:.3g} B"
                       for r in stops.itertuples()) + ".")
        + " " + ("No triangle distorts past the threshold." if distorted.empty else
                 "Distorted triangles appear in " + "; ".join(
                     f"{r.label} on {r.nodes} nodes from {r.distorted_at:.3g} B"
                     for r in distorted.itertuples()) + "."),
        "",
        "![footing cost](figures/footing_cost.png)",
        "",
    ]


def verdict(summary, table):
    """The paper's claim that EFG handles large, non-uniform deformation where FEM meets
    mesh distortion, judged on the footing: ``(verdict, measured)``.

    Every EFG run counts, whatever its essential conditions or step count (each
    :data:`METHODS` entry solved by EFG is a variant). Supported if an EFG variant reaches
    further than a fixed-mesh FEM run on the same nodes (to 0.5 B on every density, or
    to :data:`DEEP` B on the built-in nodes) and is no further from the reference curve;
    refuted if every fixed-mesh FEM run reaches at least as far as every EFG variant and
    Taylor-Hood is nearer the reference than every EFG run at every density but the
    reference's own, each pair compared over the same range (from :data:`FROM` to where
    the EFG run stops); open otherwise. ``table`` is :func:`curves`, ``summary`` its
    :func:`summary`.
    """
    deep = summary[summary.label.str.endswith(f"to {DEEP:g} B")]
    deep = deep.set_index(family(deep.label))
    base = summary[summary.label.isin(list(METHODS))]
    variants = base[meshless(base.label)]
    fixed = [m for m, (method, extra) in METHODS.items()
             if method not in EFG_METHODS and not extra]
    fem = base[base.label.isin(fixed)]
    th = fem[fem.label == REFERENCE[0]].set_index("nodes")
    efg = variants.set_index(["label", "nodes"])
    pairs = [(r, v) for r in fem.itertuples() for v in variants[
        variants.nodes == r.nodes].itertuples()]
    deep_pairs = [(deep.loc[m], deep.loc[v]) for m in fixed for v in variants.label.unique()]
    further = any(r.reached < v.reached and v.error <= r.error for r, v in pairs) or any(
        m.reached < v.reached and v.error <= m.error for m, v in deep_pairs)
    ref = table[(table.label == REFERENCE[0]) & (table.core == REFERENCE[1])]
    runs = summary[meshless(summary.label) & ~summary.label.str.endswith(f"to {DEEP:g} B")]

    def th_error(nodes, upto):
        curve = table[(table.label == REFERENCE[0]) & (table.nodes == nodes)]
        return _error(curve.settlement.to_numpy(), curve.pressure.to_numpy(), ref, upto)

    nearer = [(r.label, r.nodes, r.steps, r.reached, r.error, th_error(r.nodes, r.reached))
              for r in runs[runs.nodes != th.index[-1]].itertuples()]
    behind = (all(r.reached >= v.reached for r, v in pairs)
              and all(m.reached >= v.reached for m, v in deep_pairs)
              and all(th_e < e for *_, e, th_e in nearer))
    word = "supported" if further else "refuted" if behind else "open"
    return word, (
        "strip footing to 0.5 B (" + ", ".join(th.index) + " nodes): reached "
        + "; ".join(f"{label} " + ", ".join(f"{v:.3g}" for v in group.reached)
                    for label, group in base.groupby("label", sort=False))
        + f" B; to {DEEP:g} B on the built-in nodes: " + ", ".join(
            f"{m} {r.reached:.3g} B" for m, r in deep.iterrows())
        + f"; largest error against the finest fem-th from {FROM:g} B to where each run "
        "stops: " + "; ".join(f"{label} " + ", ".join(
            _reach(efg.loc[label, n]) for n in group.nodes)
            for label, group in variants.groupby("label", sort=False))
        + "; fem-th " + ", ".join(_reach(th.loc[n]) for n in th.index[:-1])
        + " (the finest is the reference); over each EFG run's own range, fem-th on its "
        "nodes is " + ", ".join(f"{th_e:.2g} against {e:.2g} for {label} ({n}, {steps} "
                                f"steps, to {upto:.3g} B)"
                                for label, n, steps, upto, e, th_e in nearer))


def _reach(run):
    """A run's error and the settlement [B] up to which it is taken (where the run
    stops): errors over different ranges are not like for like."""
    return f"{run.error:.2g} to {run.reached:.3g} B"
