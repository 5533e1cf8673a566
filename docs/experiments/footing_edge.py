"""Is consistent EFG's excess footing force made at the footing's edge? Force against
the footing's width.

Quoted by ``docs/theory/efg.rst`` ("The two named configurations"). If EFG's extra
stiffness on the undrained footing came from its edge (MLS spreads the change from the
prescribed settlement under the footing to the free surface beside it over a support, so
the footing acts wider than it is), the footing force ``F(a)`` at 0.1 B against the half
width ``a`` would have fem-th's slope and a larger intercept: an added width ``delta``
that scales with the support, not with ``a``. If the extra stiffness sits in the soil
under the footing, ``F(a)`` is fem-th's times a factor: a steeper slope and the same
intercept.

Every run is the built-in smooth footing (:mod:`locking`'s: 20 steps to 0.1 B, core
spacing ``h = B / core``) with the footing's end ``boundary.top.footing.to`` at the
node spacings of ``--widths``; EFG is the recommended configuration (gauss, Nitsche,
perturbation). The footing force per unit length of the half [kN/m] is the footing
pressure times ``a``. The fit ``F = c (a + delta)`` of each method's forces (least
squares over the widths) gives the slope ``c`` and the added width ``delta``, in
spacings ``h`` and in EFG's displacement support radii; fem-th has an intercept too
(the settlement is 0.1 m at every width, so a narrower footing is further into its
failure), so the test is the difference EFG - fem-th at each width: constant for an
edge effect, proportional to ``a`` for a bulk one.

``python docs/experiments/footing_edge.py`` runs 21 x 21 and 42 x 42 nodes (about 10
minutes on 2 cores); ``--cores 2 --widths 1 2 --steps 2`` is the smallest.
"""

import argparse

import numpy as np

import soilwater
from soilwater.efg.mls_supports import support_radii

import locking

#: EFG's recommended configuration, stated explicitly (defaults may change).
EFG = ("efg.integration=gauss", "efg.essential=nitsche", "efg.stabilisation=perturbation")


def run(core, spacings, method, steps=20):
    """The footing force [kN/m] at 0.1 B (in ``steps`` steps) with the half width
    ``spacings`` core spacings, or NaN when the run stops short."""
    width = spacings / core
    extra = (f"boundary.top.footing.to={width!r}", *(EFG if method == "efg" else ()))
    row = locking.run(core, steps, method, "gauss", "perturbation", extra)
    return width, row["pressure"] * locking.REFERENCE * width, row


def fit(widths, forces):
    """Least-squares ``F = c (a + delta)``: the slope ``c`` [kPa] and ``delta`` [m]."""
    slope, intercept = np.polyfit(widths, forces, 1)
    return slope, intercept / slope


def radius(core):
    """The mean MLS displacement support radius [m] of the footing case's nodes under
    the footing (initial x <= B, y >= H - B)."""
    case = locking.footing(core, 20, "gauss", "perturbation", EFG)
    x = case.nodes()
    under = (x[:, 0] <= 1.0 + 1e-9) & (x[:, 1] >= case.geometry.height - 1.0 - 1e-9)
    return float(support_radii(x, case.efg.scale_u)[under].mean())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cores", type=int, nargs="+", default=[4, 8],
                        help="spacings per B (4: 21 x 21, 8: 42 x 42)")
    parser.add_argument("--widths", type=int, nargs="+", default=[1, 2, 3, 4],
                        help="half widths in core spacings at --cores' first; scaled")
    parser.add_argument("--steps", type=int, default=20, help="steps to 0.1 B")
    args = parser.parse_args(argv)
    rows = []
    print(f"{'core':>4s} {'method':8s} {'a [m]':>6s} {'F [kN/m]':>9s} {'F/Prandtl a':>11s}")
    for core in args.cores:
        scale = core // args.cores[0]
        fits = {}
        for method in ("fem-th", "efg"):
            points = []
            for w in args.widths:
                a, force, row = run(core, w * scale, method, args.steps)
                points.append((a, force))
                rows.append({"core": core, "method": method, "a": a, "force": force,
                             "failed": row["failed"]})
                print(f"{core:4d} {method:8s} {a:6.3f} {force:9.4f} "
                      f"{force / (locking.REFERENCE * a):11.4f}"
                      + (f"  {row['failed'][:80]}" if row["failed"] else ""))
            a, force = np.array(points).T
            ok = np.isfinite(force)
            fits[method] = fit(a[ok], force[ok]) if ok.sum() >= 2 else (np.nan, np.nan)
        here = [r for r in rows if r.get("core") == core and "force" in r]
        fem = {r["a"]: r["force"] for r in here if r["method"] == "fem-th"}
        for r in here:
            if r["method"] == "efg":
                excess = r["force"] - fem[r["a"]]
                print(f"{core:4d} a {r['a']:.3f}: EFG - fem-th {excess:+.4f} kN/m "
                      f"({excess / fem[r['a']]:+.1%} of fem-th's)")
        h, r = 1.0 / core, radius(core)
        for method, (c, delta) in fits.items():
            print(f"{core:4d} {method:8s} slope {c:8.3f} kPa ({c / locking.REFERENCE:.3f} "
                  f"x Prandtl's), added width {delta:+.4f} m = {delta / h:+.2f} h = "
                  f"{delta / r:+.2f} support radii ({r:.3f} m)")
        rows.append({"core": core, "fits": fits, "h": h, "radius": r})
    return rows


if __name__ == "__main__":
    main()
