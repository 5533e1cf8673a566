"""Why consistent EFG is stiffer than fem-th on the undrained footing: volumetric locking?

Quoted by ``docs/theory/efg.rst`` ("Where the state lives"). The built-in footing
(Cam-clay, smooth rigid footing, 20 steps to 0.1 B) with the core spacing B/CORE of
:func:`soilwater.studies.harness.grids.refined`, every EFG run with penalty essential
conditions and the stabilisation named. Each run reports its nodes, displacement and
pressure unknowns, wall time, whether it reached 0.1 B, the footing pressure there over
Prandtl's for the built-in clay (6.69 kPa, whatever the variant) and the pore pressure's
change since t = 0 under the footing (initial x <= B, y >= H - B) [kPa, compression
positive]: its range and its wiggle, the largest ``|dp_w - mean of its neighbours|``
over Prandtl's pressure (a checkerboard shows as a wiggle of the order of the range; a
Delaunay triangulation of the initial nodes gives the neighbours).

* ``--sizes``: each scheme and each FEM pair of ``--fem`` (fem-th, and fem-p1p1-stab with
  EFG's unknowns) at several node sets;
* ``--variants``: the constraint removed: ``drained`` (k = 1000 m/s, p_w0 = 0, the top
  drained: p_w dissipates within a step), ``elastic`` (the linear skeleton of the clay's
  initial moduli, undrained) and ``elastic-drained``, each over fem-th's pressure;
* ``--stabilisations``: none, the perturbation at each ``--factors`` and (``gauss``)
  the projection;
* ``--supports``: the MLS supports ``efg.scale_u`` and ``efg.scale_p``;
* ``--fine``: runs at ``--fine-core`` given as ``SCHEME[,key=value...]``.

No table chosen: all five. ``python docs/experiments/locking.py`` (about half an hour
on 2 cores shared with other jobs); ``--steps 2 --core 2 --cores 2 --fem-cores 2
--variant-cores 2 --fine-core 2`` for 10 x 10 nodes.
"""

import argparse
import time

import numpy as np
import scipy.sparse as sp
from scipy.spatial import Delaunay

import soilwater
from soilwater.errors import SoilwaterError
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.studies.harness.grids import CORE, refined

#: Settlement rate of the built-in footing [m/s]: 0.1 B is reached at 10 s.
TO_TENTH = 10.0
#: EFG's essential conditions in every run (passed explicitly: defaults change).
ESSENTIAL = "penalty"
#: Overrides of each variant of the footing.
DRAINED = ("material.permeability=1000.0", "initial.pore_pressure=0.0",
           "boundary.top.water=drained")
VARIANTS = {"undrained": (), "drained": DRAINED,
            "elastic": ("material.model=elastic",),
            "elastic-drained": ("material.model=elastic", *DRAINED)}
#: The tables, in the order they run.
TABLES = ("sizes", "variants", "stabilisations", "supports", "fine")
#: Pressure of the built-in footing at Prandtl's limit [kPa]: every variant's scale.
REFERENCE = PRANDTL * undrained_strength(soilwater.load_case("strip-footing").material())


def footing(core, steps, scheme="nodal", stabilisation="none", extra=()):
    """The built-in footing at ``core`` spacings per B, ``steps`` steps to 0.1 B, EFG's
    ``scheme`` and ``stabilisation`` (later ``extra`` overrides win)."""
    return soilwater.load_case("strip-footing", *refined(core)[2:],
                               f"time.end={TO_TENTH!r}", f"time.steps={steps}",
                               f"efg.integration={scheme}", f"efg.essential={ESSENTIAL}",
                               f"efg.stabilisation={stabilisation}", *extra)


def neighbours(triangles, n):
    """Each node's mesh neighbours (a 0/1 sparse (n, n) matrix) from (T, 3) triangles."""
    i = triangles[:, [0, 1, 2, 1, 2, 0]].ravel()
    j = triangles[:, [1, 2, 0, 0, 1, 2]].ravel()
    adjacent = sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)).tocsr()
    adjacent.data[:] = 1.0
    return adjacent


def pore_pressure(case, snapshots):
    """The pore pressure's change from the first snapshot (t = 0) to the last under the
    footing: (min, max) [kPa] and the wiggle, max |dp_w - neighbours' mean| over
    :data:`REFERENCE` (compression positive)."""
    x0 = case.nodes()
    under = (x0[:, 0] <= CORE + 1e-9) & (x0[:, 1] >= case.geometry.height - CORE - 1e-9)
    p = snapshots[-1].point_data["p_w"] - snapshots[0].point_data["p_w"]
    adjacent = neighbours(Delaunay(x0).simplices, len(p))
    mean = adjacent @ p / np.asarray(adjacent.sum(axis=1)).ravel()
    return p[under].min(), p[under].max(), np.abs(p - mean)[under].max() / REFERENCE


def run(core, steps, method, scheme="nodal", stabilisation="none", extra=()):
    """One run: its size, time, reach, pressure over :data:`REFERENCE` and pore pressure.

    ``method`` is ``efg`` (with ``scheme``) or an FEM pair; returns a row dict. A run
    that stops short of 0.1 B or is refused has NaN for what it did not reach and its
    reason in ``failed`` (None otherwise).
    """
    case = footing(core, steps, scheme, stabilisation, extra)
    nodes = len(case.nodes())
    row = {"method": scheme if method == "efg" else method, "core": core, "nodes": nodes,
           "u": np.nan, "p": np.nan, "reached": False, "stabilisation": stabilisation,
           "extra": " ".join(extra), "pressure": np.nan, "pw_min": np.nan,
           "pw_max": np.nan, "wiggle": np.nan}
    start = time.perf_counter()
    try:
        result = soilwater.solve(case, method, progress=False)
    except SoilwaterError as error:
        return {**row, "seconds": time.perf_counter() - start,
                "failed": str(error).splitlines()[0]}
    row["seconds"] = time.perf_counter() - start
    h = result.history
    row.update(u=result.summary["dofs"] - nodes, p=nodes, failed=result.summary["stopped"],
               reached=len(h) > 0 and abs(h.time.iloc[-1] - TO_TENTH) < 1e-9)
    if row["reached"]:
        row["pressure"] = h["pressure@footing"].iloc[-1] / REFERENCE
        row["pw_min"], row["pw_max"], row["wiggle"] = pore_pressure(case, result.snapshots)
    return row


def show(title, rows, label=None):
    """Print ``rows`` under ``title``; ``label(row)`` names each (default its method),
    and a failed run's reason follows its row."""
    print(f"\n{title}")
    print(f"{'run':42s} {'nodes':>6s} {'u':>6s} {'p':>5s} {'s':>7s} {'0.1 B':>5s} "
          f"{'p/Prandtl':>9s} {'dp_w min':>8s} {'dp_w max':>8s} {'wiggle':>8s}")
    for r in rows:
        name = label(r) if label else r["method"]
        print(f"{name:42s} {r['nodes']:6d} {r['u']:6.0f} {r['p']:5.0f} {r['seconds']:7.1f} "
              f"{'yes' if r['reached'] else 'NO':>5s} {r['pressure']:9.4f} "
              f"{r['pw_min']:8.3g} {r['pw_max']:8.3g} {r['wiggle']:8.3g}")
        if r["failed"]:
            print(f"    {str(r['failed'])[:150]}")


def sizes(cores, fems, fem_cores, schemes, steps):
    """Each scheme at ``cores`` and each FEM pair of ``fems`` at ``fem_cores``."""
    rows = [run(c, steps, "efg", s) for c in cores for s in schemes]
    rows += [run(c, steps, m) for m in fems for c in fem_cores]
    show("Sizes: undrained footing", rows, lambda r: f"{r['method']} core {r['core']}")
    return rows


def variants(cores, names, schemes, fems, steps):
    """Each variant with each scheme and FEM pair at each core; the ratio of each
    pressure over the first pair's."""
    rows = []
    for core in cores:
        for name in names:
            extra = VARIANTS[name]
            block = [run(core, steps, m, extra=extra) for m in fems]
            block += [run(core, steps, "efg", s, extra=extra) for s in schemes]
            for r in block:
                r["variant"], r["ratio"] = name, r["pressure"] / block[0]["pressure"]
            rows += block
    show(f"Variants (ratio: over {fems[0]})", rows,
         lambda r: f"{r['variant']} {r['method']} core {r['core']} ratio {r['ratio']:.3f}")
    return rows


def stabilisations(core, schemes, factors, steps):
    """Each scheme without stabilisation, with the perturbation at each factor and
    (``gauss``, ``paper``) the projection at each factor."""
    rows = []
    for scheme in schemes:
        kinds = ["perturbation"] + (["projection"] if scheme != "nodal" else [])
        rows.append(run(core, steps, "efg", scheme))
        rows += [run(core, steps, "efg", scheme, kind,
                     (f"efg.stabilisation_factor={f!r}",))
                 for kind in kinds for f in factors]
    show(f"Stabilisations at core {core}", rows,
         lambda r: f"{r['method']} {r['stabilisation']} {r['extra']}".replace("efg.", ""))
    return rows


def supports(core, schemes, pairs, steps):
    """Each scheme with each (scale_u, scale_p) pair."""
    rows = [run(core, steps, "efg", s, extra=(f"efg.scale_u={u!r}", f"efg.scale_p={p!r}"))
            for s in schemes for u, p in pairs]
    show(f"Supports at core {core}", rows,
         lambda r: f"{r['method']} {r['extra']}".replace("efg.", ""))
    return rows


def fine(core, specs, steps):
    """Runs at ``core`` given as ``SCHEME[,key=value...]`` (``stabilisation`` among them)."""
    rows = []
    for spec in specs:
        scheme, *pairs = spec.split(",")
        keys = dict(pair.split("=", 1) for pair in pairs)
        stabilisation = keys.pop("efg.stabilisation", "none")
        extra = tuple(f"{k}={v}" for k, v in keys.items())
        rows.append(run(core, steps, "efg", scheme, stabilisation, extra))
    show(f"Fine runs at core {core}", rows,
         lambda r: f"{r['method']} {r['stabilisation']} {r['extra']}".replace("efg.", ""))
    return rows


def pair(text):
    """``U,P`` as (scale_u, scale_p)."""
    u, p = text.split(",")
    return float(u), float(p)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for table in TABLES:
        parser.add_argument(f"--{table}", action="store_true")
    parser.add_argument("--steps", type=int, default=20, help="steps to 0.1 B")
    parser.add_argument("--core", type=int, default=4,
                        help="spacings per B of all but --sizes and --fine (4: 21 x 21)")
    parser.add_argument("--cores", type=int, nargs="+", default=[4, 8, 12],
                        help="EFG's spacings per B in --sizes (8: 42 x 42 nodes)")
    parser.add_argument("--fem-cores", type=int, nargs="+", default=[2, 4, 8, 12],
                        help="the FEM pairs' spacings per B in --sizes (2: 10 x 10)")
    parser.add_argument("--fem", nargs="+", default=["fem-th", "fem-p1p1-stab"],
                        help="FEM pairs of --sizes and --variants (the first: the ratios')")
    parser.add_argument("--variant-cores", type=int, nargs="+", default=[4, 8])
    parser.add_argument("--schemes", nargs="+", default=["paper", "gauss", "nodal"])
    parser.add_argument("--variants-of", nargs="+", default=list(VARIANTS),
                        choices=list(VARIANTS), help="the variants of --variants")
    parser.add_argument("--factors", type=float, nargs="+", default=[1.0, 4.0, 16.0, 100.0],
                        help="efg.stabilisation_factor values")
    parser.add_argument("--pairs", type=pair, nargs="+",
                        default=[(1.6, 1.3), (2.0, 1.3), (1.3, 1.6), (1.3, 2.0), (1.6, 1.6),
                                 (2.0, 2.0)], help="scale_u,scale_p pairs of --supports")
    parser.add_argument("--fine-core", type=int, default=8)
    parser.add_argument("--fine-runs", nargs="+", default=[
        "gauss,efg.stabilisation=projection,efg.stabilisation_factor=16",
        "gauss,efg.stabilisation=perturbation,efg.stabilisation_factor=16",
        "nodal,efg.stabilisation=perturbation,efg.stabilisation_factor=16",
        "gauss,efg.scale_u=2.0", "nodal,efg.scale_u=2.0"],
        help="SCHEME[,key=value...] of --fine")
    args = parser.parse_args(argv)
    consistent = [s for s in args.schemes if s != "paper"]
    chosen = [t for t in TABLES if getattr(args, t)] or TABLES
    tables = {"sizes": lambda: sizes(args.cores, args.fem, args.fem_cores, args.schemes,
                                     args.steps),
              "variants": lambda: variants(args.variant_cores, args.variants_of, consistent,
                                           args.fem, args.steps),
              "stabilisations": lambda: stabilisations(args.core, consistent, args.factors,
                                                       args.steps),
              "supports": lambda: supports(args.core, consistent, args.pairs, args.steps),
              "fine": lambda: fine(args.fine_core, args.fine_runs, args.steps)}
    return {t: tables[t]() for t in chosen}


if __name__ == "__main__":
    main()
