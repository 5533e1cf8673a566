"""Is consistent EFG's stiffness on the undrained footing volumetric locking? The pore
pressure's unknowns on a coarser subset of the nodes.

Quoted by ``docs/theory/efg.rst`` ("The two named configurations"). An equal-order
pressure gives every node a volumetric constraint; if that locks, fewer constraints
should soften the footing. Here the pressure's increments live on a subset of the nodes
about ``s`` spacings apart (greedy: the boundary loop first, then bottom-left onwards, a
node taken when no taken node lies within ``0.75 s`` of its nearest-neighbour distance;
every other node of a grid for s = 2): the nodal pressure parameters are the MLS
interpolant of the subset's, ``p = P p_c``, and each step's Newton system is reduced by
``T = diag(I, P, I)`` to ``T^T K T``, ``T^T R``. The solver is patched for the
experiment only (:func:`use`); nothing in the package changes.

``python docs/experiments/coarse_pressure.py`` runs the built-in footing to 0.1 B (20
steps, 21 x 21 nodes, ``gauss``) with s = 1 to 4, penalty and Nitsche, and the drained
and elastic variants of ``locking.py`` with s = 1 and 2, beside fem-th (about 5 minutes
on 2 cores).
"""

import argparse

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from soilwater.efg import system
from soilwater.efg.essential.penalty import excess, roundoff
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.model import Model

import locking

#: The subset's spacing in node spacings (1: every node, the package's own solver).
SPACING = {"s": 1}
_ORIGINAL = {"build": Model.build.__func__, "init": system.System.__init__,
             "residual": system.System.residual, "tangent": system.System.tangent,
             "advance": system.System.advance}


def subset(nodes, loop, spacing):
    """Indices of a subset of ``nodes`` about ``spacing`` nearest-neighbour distances
    apart, the boundary ``loop``'s nodes considered first."""
    if spacing <= 1:
        return np.arange(len(nodes))
    tree = cKDTree(nodes)
    radius = 0.75 * spacing * tree.query(nodes, k=2)[0][:, 1]
    rest = np.setdiff1d(np.arange(len(nodes)), loop)
    order = np.concatenate([loop, rest[np.lexsort((nodes[rest, 0], nodes[rest, 1]))]])
    free = np.ones(len(nodes), bool)
    taken = []
    for i in order:
        if free[i]:
            taken.append(i)
            free[tree.query_ball_point(nodes[i], radius[i])] = False
    return np.sort(np.array(taken))


def _reduction(P, n, extra):
    return sp.block_diag([sp.identity(2 * n), P, sp.identity(extra)], format="csr")


def _build(cls, case):
    model = _ORIGINAL["build"](cls, case)
    model.coarse = subset(case.nodes(), model.loop, SPACING["s"])
    return model


def _init(self, model, points, disc, t0, t1, timings, load=None):
    _ORIGINAL["init"](self, model, points, disc, t0, t1, timings, load)
    self.P = None
    if getattr(model, "coarse", None) is not None:
        s = model.case.efg
        self.P = sp.csr_matrix(ShapeFunctions.build(
            points.nodes[model.coarse], points.nodes, s.weight_p, s.scale_p).phi)
        self.layout = None               # a direct solve of the reduced system


def _residual(self):
    R, scaled = _ORIGINAL["residual"](self)
    if self.P is None:
        return R, scaled
    n, sc, bc = self.n, self.model.scales, self.disc.bc
    noise_u, noise_p, noise_plate = roundoff(
        self.disc, self.points, self.du.reshape(2, n).T, self.du_bar, self.p, self.plate,
        *self._factors, self.rigid_w)
    R_u, R_p, extra = R[:2 * n], self.P.T @ R[2 * n:3 * n], R[3 * n:]
    scaled = max(excess(R_u, noise_u) / sc.force,
                 excess(R_p, abs(self.P).T @ noise_p) / sc.volume,
                 excess(extra[:1], noise_plate) / sc.force * bc.rigid.any(),
                 np.abs(extra[-1:]).max(initial=0) / sc.volume * sc.pin_pressure)
    return np.concatenate([R_u, R_p, extra]), scaled


def _tangent(self):
    K = _ORIGINAL["tangent"](self)
    if self.P is None:
        return K
    T = _reduction(self.P, self.n, K.shape[0] - 3 * self.n)
    return (T.T @ K @ T).tocsr()


def _advance(self, dx):
    if self.P is not None:
        dx = _reduction(self.P, self.n, len(dx) - 2 * self.n - self.P.shape[1]) @ dx
    _ORIGINAL["advance"](self, dx)


def use(spacing):
    """Patch the EFG solver to carry the pore pressure's unknowns on a subset
    ``spacing`` node spacings apart; ``use(1)`` puts the package's own solver back."""
    SPACING["s"] = spacing
    if spacing <= 1:
        Model.build = classmethod(_ORIGINAL["build"])
        for name in ("init", "residual", "tangent", "advance"):
            setattr(system.System, f"__{name}__" if name == "init" else name,
                    _ORIGINAL[name])
        return
    Model.build = classmethod(_build)
    system.System.__init__, system.System.residual = _init, _residual
    system.System.tangent, system.System.advance = _tangent, _advance


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--core", type=int, default=4, help="spacings per B (4: 21 x 21)")
    parser.add_argument("--steps", type=int, default=20, help="steps to 0.1 B")
    parser.add_argument("--spacings", type=int, nargs="+", default=[1, 2, 3, 4])
    args = parser.parse_args(argv)
    rows = []
    for name, extra in locking.VARIANTS.items():
        rows.append({**locking.run(args.core, args.steps, "fem-th", extra=extra),
                     "variant": name, "s": "-"})
        spacings = args.spacings if name == "undrained" else args.spacings[:2]
        essentials = ("penalty", "nitsche") if name == "undrained" else ("penalty",)
        for essential in essentials:
            for s in spacings:
                use(s)
                row = locking.run(args.core, args.steps, "efg", "gauss", "none",
                                  (*extra, f"efg.essential={essential}"))
                case = locking.footing(args.core, args.steps)
                rows.append({**row, "variant": f"{name} {essential}", "s": s,
                             "p": len(subset(case.nodes(), case.boundary_loop(), s))})
        use(1)
    for r in rows:
        r["method"] = f"{r['method']} s={r['s']}"
    locking.show("Pore pressure's unknowns on a subset s spacings apart (fem-th's p: its "
                 "vertices)", rows, lambda r: f"{r['variant']} {r['method']}")
    return rows


if __name__ == "__main__":
    main()
