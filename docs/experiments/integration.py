"""Where EFG keeps its material state (``efg.integration``), measured on the strip footing.

Quoted by ``docs/theory/efg.rst`` ("Where the state lives"). For each scheme on the
built-in footing (undrained Cam-clay, smooth rigid footing) with the core spacing B/CORE
of :func:`soilwater.studies.harness.grids.refined`:

* ``--consistency``: after each of the first steps, the carried state against the
  equilibrium state at the step's own integration points (q, L2 and worst point, over the
  step's largest q), and the out-of-balance of the carried state at the next step's start
  (dt = 0, nothing moved): its largest entry [kN/m] over the footing force and in Newton
  tolerances;
* ``--steps``: the footing pressure at 0.1 B over Prandtl's against the steps per 0.5 B,
  with the successive differences;
* ``--drift``: the specific volume's drift from its initial value at 0.1 B (exactly 0
  undrained), worst point and volume-weighted mean;
* ``--reach``: the footing pushed to ``--to`` B with ``--per`` steps per 0.5 B, each run
  stopping where a step fails: how far it gets, the pressure over Prandtl's at each
  quarter B, how often its triangles are rebuilt (``gauss``: with a transfer and a
  re-equilibration, :mod:`soilwater.efg.rebuild`; ``nodal``: re-triangulated), the
  out-of-balance of the carried state before and after the re-equilibration (worst over
  the rebuilds, in Newton tolerances), and the kink a rebuild leaves in the pressure
  curve: a step's increment less the mean of its neighbours', at the step that rebuilds
  and the next (``gauss`` re-equilibrates within its step, ``nodal`` integrates on its new
  cells from the next): the median over rebuilds of the larger of the two, the largest,
  and the median over the other steps.

``python docs/experiments/integration.py --steps --core 4 --schemes paper gauss nodal``
(about two minutes; ``--core 2`` for 10 x 10 nodes). ``python
docs/experiments/integration.py --reach --core 2 --to 2`` (about a minute).

The runs are penalty without stabilisation (``efg.essential`` and ``efg.stabilisation``
passed explicitly; ``--set`` overrides them).
"""

import argparse
from collections import defaultdict

import numpy as np

import soilwater
from soilwater.efg import solver
from soilwater.efg.discretisation import discretise
from soilwater.efg.model import Model
from soilwater.efg.system import System
from soilwater.material.kinematics import invariants
from soilwater.nonlinear.newton import TOLERANCE, new_counts, newton
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.studies.harness.grids import refined

#: Settlement rate of the built-in footing [m/s]: 0.1 B is reached at 10 s.
TO_TENTH = 10.0
#: The settings every run passes (their defaults are not the measured ones' to rely on).
MEASURED = ("efg.essential=penalty", "efg.stabilisation=none")


def footing(core, scheme, steps_per_half, end=TO_TENTH, extra=()):
    """The built-in footing with ``core`` spacings per B, the scheme, to ``end`` [s]."""
    steps = max(1, round(steps_per_half * end / 50.0))
    return soilwater.load_case("strip-footing", *refined(core)[2:],
                               f"efg.integration={scheme}", f"time.end={end!r}",
                               f"time.steps={steps}", *MEASURED, *extra)


def _stats():
    """Newton's statistics at zero: its counts and the phase timings."""
    return {"timings": defaultdict(float), **new_counts()}


def _system(model, points, t0, t1):
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                      defaultdict(float), points.cells)
    return System(model, points, disc, t0, t1, defaultdict(float))


def consistency(core, schemes, steps_per_half, count):
    """The carried state against equilibrium, and its out-of-balance, step by step."""
    print("scheme  step  settlement [B]  q error L2  q error max  "
          "out-of-balance/force  /tolerance")
    for scheme in schemes:
        case = footing(core, scheme, steps_per_half, end=50.0)
        model = Model.build(case)
        points, times = solver._initial_points(model), case.times()
        for k in range(count):
            system = _system(model, points, times[k], times[k + 1])
            newton(system, _stats())
            points = system.finish()
            points.cells = solver._cells(model, points.nodes, system.points.cells)
            carried = points.stress
            if not model.consistent:            # the nodes' state, back at the points
                carried = system.disc.su.phi @ carried
            _, q_eq = invariants(system.stress)
            _, q = invariants(carried)
            R, scaled = _system(model, points, times[k + 1], times[k + 1]).residual()
            force = np.abs(points.reactions).max()
            n = len(points.nodes)
            print(f"{scheme:7s} {k + 1:4d}  {0.01 * times[k + 1]:14.3f}  "
                  f"{np.linalg.norm(q - q_eq) / np.linalg.norm(q_eq):10.2%}  "
                  f"{np.abs(q - q_eq).max() / q_eq.max():11.2%}  "
                  f"{np.abs(R[:2 * n]).max() / force:20.2%}  {scaled / TOLERANCE:10.3g}")


def steps(core, schemes, counts, extra=()):
    """Pressure at 0.1 B over Prandtl's per scheme and steps per 0.5 B; returns
    {scheme: [pressure, ...]} (NaN where a run stopped short)."""
    table = {}
    for scheme in schemes:
        row = []
        for per in counts:
            case = footing(core, scheme, per, extra=extra)
            h = soilwater.solve(case, "efg", progress=False).history
            reached = abs(h.time.iloc[-1] - TO_TENTH) < 1e-9
            row.append(h["pressure@footing"].iloc[-1]
                       / (PRANDTL * undrained_strength(case.material())) if reached
                       else np.nan)
        table[scheme] = row
        differences = "  ".join(f"{d:+.4f}" for d in np.diff(row))
        print(f"{scheme:7s} " + "  ".join(f"{p:.4f}" for p in row)
              + f"   differences {differences}")
    return table


def drift(core, schemes, counts):
    """The specific volume's drift at 0.1 B: worst point and volume-weighted mean."""
    print("scheme  steps/0.5B  max |v/v0 - 1|  mean |v/v0 - 1|")
    for scheme in schemes:
        for per in counts:
            case = footing(core, scheme, per)
            model = Model.build(case)
            points, times = solver._initial_points(model), case.times()
            v0 = points.state["v"]
            for t0, t1 in zip(times[:-1], times[1:]):
                points, _, _ = solver._step(model, points, t0, t1, _stats())
            d = np.abs(points.state["v"] / v0 - 1)
            w = points.cells.weights if model.consistent else None
            print(f"{scheme:7s} {per:10d}  {d.max():14.3%}  "
                  f"{np.average(d, weights=w):15.4%}")


def reach(core, schemes, per, to, extra=()):
    """Each scheme's footing pushed to ``to`` B (module docstring); returns the rows."""
    print("scheme  reached [B]  " + "  ".join(f"{q:g} B" for q in _quarters(to))
          + "  rebuilds  out-of-balance before/after [tol]  kink at rebuilds median/max"
          + "  elsewhere median")
    rows = []
    for scheme in schemes:
        case = footing(core, scheme, per, end=10 * TO_TENTH * to,
                       extra=("time.on_failure=stop", *extra))
        result = soilwater.solve(case, "efg", progress=False)
        h = result.history
        pressure = (h["pressure@footing"].to_numpy()
                    / (PRANDTL * undrained_strength(case.material())))
        settlement = h.time.to_numpy() / (10 * TO_TENTH)
        at = {q: float(pressure[np.isclose(settlement, q)][0])
              if np.isclose(settlement, q).any() else np.nan for q in _quarters(to)}
        rebuilt, kink = _rebuilt(result.snapshots), np.abs(_kinks(pressure))
        touched = rebuilt | np.insert(rebuilt[:-1], 0, False)       # and the step after
        worse = np.fmax(kink, np.append(kink[1:], np.nan))[rebuilt]
        records = result.summary.get("rebuild_records", [])
        balance = [max(r[f"out_of_balance_{k}"] for r in records) / TOLERANCE
                   if records else np.nan for k in ("before", "after")]
        row = {"scheme": scheme, "core": core, "reached": float(settlement[-1]),
               "pressure": at, "rebuilds": int(rebuilt.sum()), "out_of_balance": balance,
               "kink": [_finite(np.median, worse), _finite(np.max, kink[touched]),
                        _finite(np.median, kink[~touched])],
               "rebuild_steps": (np.flatnonzero(rebuilt) + 1).tolist(),
               "stopped": result.summary["stopped"]}
        rows.append(row)
        print(f"{scheme:7s} {row['reached']:11.3f}  "
              + "  ".join(f"{p:.4f}" for p in at.values())
              + f"  {row['rebuilds']:8d}  {balance[0]:10.3g} / {balance[1]:.3g}"
              + "  {:.4f} / {:.4f}  {:.4f}".format(*row["kink"]))
    return rows


def _finite(statistic, values):
    """``statistic`` of the finite ``values``, NaN when there are none."""
    values = values[np.isfinite(values)]
    return float(statistic(values)) if len(values) else np.nan


def _quarters(to):
    """The settlements [B] a pressure is reported at: every quarter B up to ``to``."""
    return np.arange(1, round(4 * to) + 1) / 4


def _rebuilt(snapshots):
    """Whether each step's triangles differ from the step before's (from the snapshots'
    cells, one per step after the initial one; never for the paper's cells, written as
    none)."""
    n = len(snapshots[0].points)
    if not snapshots[0].cells:
        return np.zeros(len(snapshots) - 1, dtype=bool)
    keys = [np.sort(np.ravel_multi_index(np.sort(s.cells[0][1], axis=1).T, (n, n, n)))
            for s in snapshots]
    return np.array([len(a) != len(b) or not np.array_equal(a, b)
                     for a, b in zip(keys[:-1], keys[1:])])


def _kinks(pressure):
    """Each step's pressure increment less the mean of its neighbours' (NaN at the ends):
    a jump the step adds to a smooth curve."""
    dp = np.diff(pressure, prepend=0.0)
    kink = np.full(len(dp), np.nan)
    kink[1:-1] = dp[1:-1] - (dp[:-2] + dp[2:]) / 2
    return kink


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--consistency", action="store_true")
    parser.add_argument("--steps", action="store_true")
    parser.add_argument("--drift", action="store_true")
    parser.add_argument("--reach", action="store_true")
    parser.add_argument("--to", type=float, default=1.0,
                        help="settlement --reach pushes the footing to [B]")
    parser.add_argument("--per", type=int, default=50, help="steps per 0.5 B of --reach")
    parser.add_argument("--core", type=int, default=4,
                        help="spacings per footing width B (4: 21 x 21 nodes)")
    parser.add_argument("--schemes", nargs="+", default=["paper", "gauss", "nodal"])
    parser.add_argument("--counts", type=int, nargs="+", default=[25, 50, 100, 200],
                        help="steps per 0.5 B")
    parser.add_argument("--first", type=int, default=6,
                        help="steps measured by --consistency (at the first count)")
    parser.add_argument("--set", nargs="*", default=[], help="more overrides, key=value")
    args = parser.parse_args(argv)
    out = {}
    if args.consistency:
        consistency(args.core, args.schemes, args.counts[0], args.first)
    if args.steps:
        out["steps"] = steps(args.core, args.schemes, args.counts, tuple(args.set))
    if args.drift:
        drift(args.core, args.schemes, args.counts)
    if args.reach:
        out["reach"] = reach(args.core, args.schemes, args.per, args.to, tuple(args.set))
    return out


if __name__ == "__main__":
    main()
