"""``soilwater infsup``: the numerical inf-sup test of every pair, on the solvers' own spaces.

The test (:mod:`soilwater.diagnostics.infsup`) runs on a unit square of ``n x n`` grid nodes, the
unconfined-compression case with ``geometry.width = height = 1``, ``layout = "grid"``
and the user's ``--set`` overrides (e.g. ``efg.weight_u=exp:0.5``). Each method builds
the three matrices from the shape functions and quadrature its solver uses:

* FEM pairs: scikit-fem bases of :mod:`soilwater.fem.spaces` with the pair's Gauss rule;
* EFG: MLS shape functions of u and p_w (``[efg]`` weights and scale factors) at the
  integration points a run of its ``efg.integration`` starts with (the background cells'
  of ``efg.cells`` and ``efg.order``; nodal: the nodes, gradients smoothed over their
  cells). The divergence is
  that of the continuity equation, MLS trial gradients (the VCI correction acts on the
  momentum equation's test gradients only).

Boundary variants: ``free`` (the whole displacement space) and ``dirichlet`` (``v = 0``
on the boundary, the Chapelle-Bathe standard). For FEM the boundary DOFs are removed. MLS
shape functions do not interpolate, so for EFG the subspace is the null space of the
displacement values at :data:`SAMPLES` Gauss points per boundary segment (singular values
below :data:`RCOND` of the largest count as zero): ``v`` vanishes there, not by penalty.
Under ``dirichlet`` the constant pressure is a zero mode of every pair and is not counted.

Stabilised pairs add their pressure term to the Schur complement, in units of the P-wave
modulus M: ``fem-p1p1-stab`` and EFG with ``efg.stabilisation = "perturbation"`` add
``(h^2/4) L``, L the pressure Laplacian (the solvers' ``beta = h^2 / (4 M)``,
:attr:`soilwater.physics.scales.Scales.perturbation`); EFG with ``"projection"`` adds ``(M/G) F``, F
the cell-fluctuation form on the background cells (``tau = 1/G``,
:func:`soilwater.physics.weakform.fluctuation`). Both are times ``efg.stabilisation_factor``.
"""

import os
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg as sla
import scipy.sparse as sp
from tqdm import tqdm

import soilwater.efg.solver
import soilwater.fem.solver
from soilwater.efg.assembly import Pattern, scatter
from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.efg.discretisation import discretise
from soilwater.efg.mls import ShapeFunctions
from soilwater.fem.assembly import Shapes, block
from soilwater.fem.spaces import PAIRS, Space, cell_bases
from soilwater.errors import InputError, require
from soilwater.diagnostics.infsup import coefficients, inf_sup
from soilwater.case.loader import load_case
from soilwater.case.schema import apply_override
from soilwater.case.validation import case_from_dict
from soilwater.linalg.environment import available_memory

BOUNDARIES = ("free", "dirichlet")
SIZES = (5, 9, 17, 33)
#: Gauss points per boundary segment at which an EFG displacement of the ``dirichlet``
#: subspace vanishes (more than the nodes whose supports reach a segment).
SAMPLES = 8
#: Relative singular value below which a boundary-value combination counts as zero.
RCOND = 1e-10
#: A pair passes when beta levels off: the local slope of log beta against log h at
#: most this over each of the last two refinements (P1/P1 decays with slope 0.6 to 1;
#: 0.2 is a loss of 13 % per halving of h).
LEVEL_SLOPE = 0.2
#: Columns of the CSV.
COLUMNS = ("method", "weights", "scale_u", "scale_p", "boundary", "n", "h", "beta",
           "zero_modes")


def square(n, overrides=()):
    """The unit square of ``n x n`` grid nodes that the test runs on (a Case): the
    unconfined compression without its probes, then ``overrides``."""
    data = load_case("unconfined-compression").to_dict()
    data.pop("probes")
    for text in ("geometry.width=1.0", "geometry.height=1.0", f"discretisation.nx={n}",
                 f"discretisation.ny={n}", "discretisation.layout=grid", *overrides):
        apply_override(data, text)
    return case_from_dict(data)


def write(out, methods, sizes=SIZES, boundaries=BOUNDARIES, overrides=()):
    """``soilwater infsup``: measure, then write the CSV ``out`` and the figure beside it
    (``out`` with suffix ``.png``); nothing is written when a measurement fails.

    Returns
    -------
    list of Path
        The CSV and the figure.
    """
    from soilwater.diagnostics import figures as stability_figures
    from soilwater.targets import check_output_file, naming, publish, write_csv

    out = Path(out)
    require(out.suffix == ".csv", f"--out {out}: name a CSV file, e.g. infsup.csv")
    figure = out.with_suffix(".png")
    out, figure = check_output_file(out, COLUMNS), check_output_file(figure)
    table = measure(methods, sizes, boundaries, overrides, progress=True)
    with naming(figure):
        figure.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=figure.parent, prefix=f".{figure.name}.",
                                   suffix=".png")
        os.close(fd)
    try:
        with naming(figure):
            stability_figures.infsup(table, slopes(table), tmp)
            publish(tmp)
        write_csv(table, out)
        with naming(figure):
            os.replace(tmp, figure)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return [out, figure]


def memory(n):
    """Bytes of the dense matrices of :func:`soilwater.diagnostics.infsup.inf_sup` on n x n
    nodes, bounded above: ``8 (3 n_p^2 + 2 n_p n_u)`` with ``n_p = n^2`` pressure and
    ``n_u = 8 n^2`` displacement unknowns (the quadratic pairs' count).

    >>> round(memory(33) / 2**20)
    172
    """
    n_p = n**2
    return 8 * (3 * n_p**2 + 2 * n_p * 8 * n_p)


def measure(methods, sizes=SIZES, boundaries=BOUNDARIES, overrides=(), progress=False):
    """The inf-sup table: one row per method, boundary variant and size.

    Parameters
    ----------
    methods : iterable of str
        ``efg`` or FEM pairs of :data:`soilwater.fem.spaces.PAIRS`.
    sizes : iterable of int
        Nodes per side (>= 3).
    boundaries : iterable of str
        :data:`BOUNDARIES`.
    overrides : iterable of str
        ``section.key=value`` entries applied to every square (EFG settings).
    progress : bool
        Show a progress bar.

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS`; ``beta`` dimensionless, ``h`` the nodal spacing [m]; the scale
        factors are empty for FEM pairs.
    """
    known = ("efg", *PAIRS)
    for method in methods:
        require(method in known, f"--methods: {method!r} is unknown: use "
                f"{', '.join(known)}")
    for n in sizes:
        require(n >= 3, f"--sizes: {n} nodes per side is too few: use 3 or more")
    largest, free = max(sizes, default=3), available_memory()
    if memory(largest) > free:
        fits = int((free / memory(1)) ** 0.25)
        raise InputError(f"--sizes: {largest} nodes per side needs about "
                         f"{memory(largest) / 2**30:.3g} GiB for the test's dense matrices, "
                         f"more than the {free / 2**30:.3g} GiB free: use at most {fits} "
                         "nodes per side")
    for boundary in boundaries:
        require(boundary in BOUNDARIES, f"boundary {boundary!r}: use free or dirichlet")
    rows = []
    runs = [(m, n) for m in methods for n in sizes]
    for method, n in tqdm(runs, desc="infsup", unit="size", disable=not progress or None,
                          leave=False):
        case = square(n, overrides)
        forms = _efg(case) if method == "efg" else _fem(case, method)
        for boundary in boundaries:
            beta, zero = inf_sup(forms["S"], forms["B"], forms["T"], forms[boundary],
                                 hydrostatic=boundary == "dirichlet", C=forms["C"])
            rows.append({"method": method, "weights": forms["weights"],
                         "scale_u": forms["scale_u"], "scale_p": forms["scale_p"],
                         "boundary": boundary, "n": n, "h": 1.0 / (n - 1), "beta": beta,
                         "zero_modes": zero})
    return pd.DataFrame(rows, columns=list(COLUMNS))


def slopes(table):
    """Whether beta levels off, per (method, weights, scales, boundary) group.

    ``slope`` is the largest local slope ``d log beta / d log h`` of the last two
    refinements (infinite where beta is zero); a group is ``stable`` when it is at most
    :data:`LEVEL_SLOPE` and at least three refinements were measured. Local slopes, not
    a fit: a coarse grid whose beta rises before it falls must not pass.
    """
    keys = ["method", "weights", "scale_u", "scale_p", "boundary"]
    rows = []
    for key, group in table.groupby(keys, sort=False):
        g = group.sort_values("h", ascending=False)
        with np.errstate(divide="ignore"):
            local = np.diff(np.log(g.beta.to_numpy())) / np.diff(np.log(g.h.to_numpy()))
        last = local[-2:] if (g.beta.to_numpy()[-3:] > 0).all() else np.array([np.inf])
        slope = float(last.max()) if last.size else np.inf
        rows.append({**dict(zip(keys, key)), "slope": slope,
                     "stable": bool(slope <= LEVEL_SLOPE and len(g) >= 4)})
    return pd.DataFrame(rows)


#: The report's EFG settings: the paper's weight pairs at two scale factors with no
#: pressure stabilisation, each stabilisation (the perturbation is the recommended
#: configuration's), and nodal integration with and without the perturbation.
REPORT_EFG = {f"{label}, scale {scale:g}": (f"efg.weight_u={u}", f"efg.weight_p={p}",
                                            f"efg.scale_u={scale}", f"efg.scale_p={scale}",
                                            "efg.stabilisation=none")
              for label, (u, p) in {"Q/Q": ("quartic", "quartic"),
                                    "E-A/E-A": ("exp:0.5", "exp:0.5"),
                                    "E-A/E-B": ("exp:0.5", "exp:0.25")}.items()
              for scale in (1.3, 2.0)}
REPORT_EFG.update({f"Q/Q, scale 1.3, {kind}": (f"efg.stabilisation={kind}",)
                   for kind in ("perturbation", "projection")})
REPORT_EFG.update({f"Q/Q, scale 1.3, nodal, {kind}": ("efg.integration=nodal",
                                                       f"efg.stabilisation={kind}")
                   for kind in ("none", "perturbation")})


def report_table(sizes=SIZES):
    """The report's inf-sup table: every FEM pair and :data:`REPORT_EFG`."""
    return pd.concat([measure(list(PAIRS), sizes)]
                     + [measure(["efg"], sizes, overrides=o) for o in REPORT_EFG.values()],
                     ignore_index=True)


def _fem(case, method):
    """S, B, T, C and the boundary variants of an FEM pair on the case's mesh."""
    space = Space.build(case, method)
    ub, pb = cell_bases(space.mesh0, space.pair)
    u, p = Shapes.of(ub), Shapes.of(pb)
    gram, div, mass, stab = coefficients(
        ub.dx.ravel(), case.geometry.height,
        _in_modulus(soilwater.fem.solver.Model.build(case, method)))
    edge = np.unique(np.concatenate(list(space.u_dofs.values())))
    interior = np.setdiff1d(np.arange(2 * space.n_u), np.concatenate([edge, space.n_u + edge]))
    pair = space.pair
    return {"S": block(u, u, gram), "B": block(p, u, div), "T": block(p, p, mass),
            "C": block(p, p, stab), "free": None,
            "dirichlet": sp.eye(2 * space.n_u, format="csr")[:, interior],
            "weights": f"{pair.u_element.__name__}/{pair.p_element.__name__}",
            "scale_u": "", "scale_p": ""}


def _efg(case):
    """S, B, T, C and the boundary variants of EFG on the case's nodes, with the
    integration points and shape functions its ``efg.integration`` starts a run with
    (:func:`soilwater.efg.discretisation.discretise` on the solver's first cells; nodal:
    the nodes with gradients smoothed over their cells)."""
    s, nodes, loop = case.efg, case.nodes(), case.boundary_loop()
    model = soilwater.efg.solver.Model.build(case)
    disc = discretise(model, nodes, nodes, defaultdict(float),
                      soilwater.efg.solver._cells(model, nodes))
    gram, div, mass, stab = coefficients(disc.w, case.geometry.height, _in_modulus(model))
    C = (_efg_block(disc.sp, disc.sp, stab)
         + model.tau * model.scales.modulus * disc.fluctuation)
    samples = boundary_points(nodes, loop, segment_edges(nodes, loop, case.geometry),
                              order=SAMPLES)
    at_boundary = ShapeFunctions.build(nodes, samples.points, s.weight_u, s.scale_u,
                                       key="efg.scale_u").phi.toarray()
    zero = sla.null_space(at_boundary, rcond=RCOND)
    return {"S": _efg_block(disc.su, disc.su, gram), "B": _efg_block(disc.sp, disc.su, div),
            "T": _efg_block(disc.sp, disc.sp, mass), "C": C,
            "free": None, "dirichlet": sla.block_diag(zero, zero),
            "weights": f"{s.weight_u}/{s.weight_p}" + "".join(
                f"+{value}" for value in ("nodal" if s.integration == "nodal" else "none",
                                          s.stabilisation) if value != "none"),
            "scale_u": s.scale_u, "scale_p": s.scale_p}


def _efg_block(test, trial, coeff):
    pattern = Pattern.build((test, trial))
    return pattern.matrix(scatter(pattern, test, trial, coeff), *coeff.fields)


def _in_modulus(model):
    """A solver model's flow-equation perturbation ``beta`` (0 when unstabilised) times
    the P-wave modulus [m2]: the units of ``S``."""
    return model.beta * model.scales.modulus
