"""The size plan of ``make bench``: which runs, at which sizes, on which linear solver.

Sizes are requested node counts (a run's grid has the nearest (3k + 1) x (4k + 1) count,
within 10 %). Every run is one step of the unconfined-compression geometry
(:func:`compression`). From :data:`LARGE_FROM` nodes only :data:`LARGE_METHODS` with
:data:`LARGE_MATERIALS` run; the linear solver is the direct one (:func:`direct`) below
:data:`KRYLOV_FROM` nodes and ``"krylov"`` from there, and from :data:`BOTH_FROM` nodes
:data:`LARGE_METHODS` run on both (:func:`plan`). EFG runs once per integration scheme
(:data:`SCHEMES`) wherever it runs. A run is stopped after :func:`time_limit` seconds.
"""

import dataclasses
from typing import NamedTuple

import numpy as np

from soilwater.case.loader import load_case
from soilwater.efg.settings import INTEGRATIONS
from soilwater.errors import InputError
from soilwater.linalg import backends as linear
from soilwater.linalg.backends import available, linear_solver

#: Requested node counts of the default run.
SIZES = (1_000, 3_000, 10_000, 30_000, 100_000, 300_000, 1_000_000)
#: Smallest node count ``--sizes`` accepts (the grid has at least 10 x 13 nodes).
MIN_SIZE = 100
METHODS = ("efg", "fem-p1p1", "fem-th", "fem-p1p1-stab")
MATERIALS = ("cam-clay", "elastic")
#: EFG's integration schemes (``efg.integration``): every EFG run is made once per scheme.
SCHEMES = INTEGRATIONS
#: From this many (requested) nodes only :data:`LARGE_METHODS` with
#: :data:`LARGE_MATERIALS` run, under :data:`LARGE_TIME_LIMIT`: EFG against the stabilised
#: P1-P1 at 10^6 nodes, within the run time of :mod:`soilwater.studies.bench.study`.
LARGE_FROM = 300_000
LARGE_METHODS = ("efg", "fem-p1p1-stab")
LARGE_MATERIALS = ("cam-clay",)
#: From this many (requested) nodes the tangents are solved by the iterative back-end
#: ``soilwater.linalg.backends.linear_solver("krylov")``; below, by the direct one
#: (:func:`direct`): where the default back-end turns iterative
#: (:data:`soilwater.linalg.backends.KRYLOV_FROM` unknowns, three per node).
KRYLOV_FROM = linear.KRYLOV_FROM // 3
#: From this many (requested) nodes up to :data:`KRYLOV_FROM`, :data:`LARGE_METHODS` run
#: on both back-ends, with every material: the step targets take each method on its
#: faster one, measured, and the Krylov path's growth spans 10^4 to 10^6.
BOTH_FROM = 10_000
#: Seconds after which one run below :data:`LARGE_FROM` nodes is stopped (recorded, not
#: timed); :data:`LARGE_TIME_LIMIT` from there.
TIME_LIMIT = 240.0
LARGE_TIME_LIMIT = 900.0
#: Largest (requested) size of the shape-function comparison (MLS against CellBasis);
#: beyond it the MLS build would take minutes and gigabytes in the bench's own process.
SHAPES_UP_TO = 100_000
#: Linear elastic skeleton of the elastic runs (kPa), at the case's p'0.
ELASTIC = (("model", "elastic"), ("E", 200.0), ("nu", 0.3), ("p0", 3.0))


def parse_sizes(text):
    """The node counts of ``--sizes``: comma-separated whole numbers, ``1e6`` allowed.

    Raises
    ------
    InputError
        One line naming the entry that is not a node count of at least :data:`MIN_SIZE`.

    Examples
    --------
    >>> parse_sizes("1000, 3e5,1e6")
    [1000, 300000, 1000000]
    """
    sizes = []
    for part in text.split(","):
        try:
            value = float(part)
        except ValueError:
            value = np.nan
        if not (np.isfinite(value) and value == round(value) and value >= MIN_SIZE):
            raise InputError(f"--sizes {text!r}: {part.strip()!r} is not a node count; use "
                             f"whole numbers of at least {MIN_SIZE}, e.g. 1000,3000,1e5")
        sizes.append(int(value))
    return sizes


def compression(nodes, material="cam-clay", krylov=False, integration="paper"):
    """The benchmark case: unconfined compression on a grid of about ``nodes`` nodes.

    Parameters
    ----------
    nodes : int
        Wanted node count; the grid is (3k + 1) x (4k + 1) with square spacing.
    material : {"cam-clay", "elastic"}
        The case's Cam-clay (Table 1) or the linear elastic :data:`ELASTIC`.
    krylov : bool
        EFG as the Krylov back-end needs it: Nitsche's essential conditions (a penalty's
        diagonal spans 1e6, so a small residual says nothing of the error) and the
        perturbation stabilisation (the case is undrained: without it the pressure Schur
        complement of equal-order MLS is near singular and FGMRES stalls); else penalty
        conditions and no stabilisation. Both are set explicitly, not left to defaults.
    integration : str
        EFG's ``efg.integration`` (:data:`SCHEMES`).

    Examples
    --------
    >>> len(compression(1000).nodes())
    1036
    """
    k = max(1, round(np.sqrt(nodes / 12)))
    case = load_case("unconfined-compression", [
        f"discretisation.nx={3 * k + 1}", f"discretisation.ny={4 * k + 1}",
        "discretisation.layout=grid", "time.steps=1", "time.end=0.2",
        f'efg.integration="{integration}"',
        *(['efg.essential="nitsche"', 'efg.stabilisation="perturbation"'] if krylov
          else ['efg.essential="penalty"', 'efg.stabilisation="none"'])])
    if material == "elastic":
        case = dataclasses.replace(case, material_spec=ELASTIC)
    return case


def direct():
    """The direct back-end of the bench: ``"pardiso"`` where ``pypardiso`` imports, else
    ``"superlu"`` (whatever ``SOILWATER_LINEAR_SOLVER`` says)."""
    return "pardiso" if available("pardiso") else "superlu"


def solver_for(nodes):
    """The linear solver of a run of ``nodes`` requested nodes: :func:`direct` below
    :data:`KRYLOV_FROM`, ``"krylov"`` from there.

    Examples
    --------
    >>> solver_for(KRYLOV_FROM)
    'krylov'
    """
    return "krylov" if nodes >= KRYLOV_FROM else direct()


def time_limit(nodes):
    """Seconds after which a run of ``nodes`` requested nodes is stopped."""
    return LARGE_TIME_LIMIT if nodes >= LARGE_FROM else TIME_LIMIT


def usable(solver):
    """True if ``soilwater.linalg.backends.linear_solver(solver)`` accepts the back-end here (a
    back-end it does not know, or PARDISO without pypardiso, raises InputError).

    Examples
    --------
    >>> usable("superlu"), usable("no-such-solver")
    (True, False)
    """
    try:
        with linear_solver(solver):
            return True
    except InputError:
        return False


#: Runs the plan skips: ``(method, scheme, solver)``: the (requested) node count from which
#: it is skipped and why (the report shows the reason in the run's row). Nodal
#: integration on Krylov, one step on 2 shared cores: 348 FGMRES iterations at 10^4 nodes
#: (paper and gauss 61), 504 at 3 x 10^4 (gauss 63), and at 10^5 no end after 890 s
#: where paper's step took 154 s (``docs/studies/speed.rst``).
SKIPS = {("efg", "nodal", "krylov"): (
    LARGE_FROM, "FGMRES iterations grow with size under nodal integration (504 against 63 "
    "at 3e4 nodes): a step would pass the time limit")}


def skipped(method, integration, solver, nodes):
    """Why the plan skips a run of ``method`` with EFG's scheme ``integration`` on
    ``solver`` at ``nodes`` requested nodes (:data:`SKIPS`), "" if it runs it.

    Examples
    --------
    >>> skipped("efg", "nodal", "krylov", LARGE_FROM) != ""
    True
    >>> skipped("efg", "nodal", "krylov", LARGE_FROM - 1), skipped("efg", "gauss", "krylov", 10**6)
    ('', '')
    """
    start, reason = SKIPS.get((method, integration, solver), (np.inf, ""))
    return reason if nodes >= start else ""


class Run(NamedTuple):
    """One run of :func:`plan`: one step of :func:`compression`.

    ``nodes`` is the requested node count; ``integration`` EFG's scheme ("-" for FEM);
    ``limit`` the seconds after which it is stopped; ``ready`` EFG as the Krylov back-end
    needs it (:func:`compression`'s ``krylov``); ``skip`` why it is not run, "" if it is.
    """

    nodes: int
    material: str
    method: str
    integration: str
    solver: str
    limit: float
    ready: bool
    skip: str = ""

    @property
    def scheme(self):
        """``efg.integration`` of the run's case: its scheme; for FEM, which reads no EFG
        setting, the paper's."""
        return "paper" if self.integration == "-" else self.integration


def plan(sizes=SIZES, methods=METHODS, materials=MATERIALS, schemes=SCHEMES):
    """The runs of :func:`~soilwater.studies.bench.runs.steps`, a :class:`Run` each, sizes
    in the given order.

    From :data:`LARGE_FROM` nodes only :data:`LARGE_METHODS` with :data:`LARGE_MATERIALS`;
    from :data:`BOTH_FROM` to :data:`KRYLOV_FROM` :data:`LARGE_METHODS` run on the direct
    back-end and then on ``"krylov"``, and on PARDISO EFG runs a second time as the Krylov
    back-end needs it (``ready``, :func:`compression`'s ``krylov``), where PARDISO
    factorises it in single precision (:attr:`soilwater.linalg.layout.Layout.single`).
    ``ready`` is True for every Krylov run. Every EFG run is made once per scheme of
    ``schemes``, in that order; a run :func:`skipped` gives is planned with its reason.

    Examples
    --------
    >>> [run[:5] for run in plan([1_000_000], ("efg", "fem-th"), schemes=("gauss",))]
    [(1000000, 'cam-clay', 'efg', 'gauss', 'krylov')]
    >>> [run.solver for run in plan([BOTH_FROM], ("efg",), ("elastic",), ("paper",))][-1:]
    ['krylov']
    """
    runs = []
    for nodes in sizes:
        for material in materials:
            for method in methods:
                if nodes >= LARGE_FROM and not (method in LARGE_METHODS
                                                and material in LARGE_MATERIALS):
                    continue
                default = solver_for(nodes)
                solvers = [(default, default == "krylov")]
                if method in LARGE_METHODS and BOTH_FROM <= nodes < KRYLOV_FROM:
                    if method == "efg" and direct() == "pardiso":
                        solvers.append(("pardiso", True))
                    solvers.append(("krylov", True))
                runs += [Run(nodes, material, method, scheme, solver, time_limit(nodes), ready,
                             skipped(method, scheme, solver, nodes))
                         for scheme in (schemes if method == "efg" else ("-",))
                         for solver, ready in solvers]
    return runs
