"""Updated-Lagrangian u-p EFG solver: Biot consolidation with finite-strain Cam-clay.

Every node carries a displacement and a pore pressure parameter; displacement and pore
pressure each have their own MLS weight and scale factor (``[efg]`` of the case). A step
from t_n to t_(n+1) is solved on the configuration x_n (shape functions and background
cells rebuilt there) for the displacement increment ``du`` and ``p_w`` at t_(n+1). Its
integrand and consistent tangent are :mod:`soilwater.physics.weakform`'s (equilibrium with
``J sigma F^-T`` on x_n, backward-Euler continuity), shared with the FEM reference; the
stress is the material's return mapping with the midpoint stretching and the
Hughes-Winget spin (:func:`soilwater.nonlinear.newton.material_update`).

Newton's method and the reuse of a factorisation within a step are
:mod:`soilwater.nonlinear.newton`'s, the cut-backs :mod:`soilwater.nonlinear.march`'s, the
scales :mod:`soilwater.physics.scales`'. A step converges when the displacement residual
is below ``TOLERANCE`` times the force scale and the continuity residual below
``TOLERANCE`` times the volume scale, each residual entry counted beyond its round-off
level: the penalty forces on boundary rows are known only to ``eps x sum |terms|``
(:func:`soilwater.efg.essential.penalty.roundoff`), which exceeds the tolerance on fine
grids. A step that does not converge, inverts a background cell or fails in the material
is halved up to :data:`soilwater.nonlinear.march.MAX_CUTS` times before the run stops
with one clear error.

The initial state (:func:`soilwater.physics.geostatic.initial_state`, uniform or geostatic)
is set at the material points, and its total stress ``sigma0 . n`` at each boundary
point's initial position loads the boundary, with the edge tractions; under gravity the
buoyant weight at the integration points (:mod:`soilwater.physics.geostatic`) loads the
domain. A gravity start loads the uniform state with its weight, drained, by this
solver's own steps (:mod:`soilwater.nonlinear.gravity_start`), and the run starts where
that left the material points, the nodes and the boundary gaps.

Where the material state lives is ``efg.integration``. With ``"gauss"`` it lives at the
Gauss points of Delaunay triangles of the nodes, which move with the nodes: each step
starts from the stresses and states that satisfied equilibrium at the end of the last, and
a step that would turn a triangle over is cut back; after a step whose worst triangle is
below ``efg.rebuild_quality`` the nodes are re-triangulated, the state carried to the new
Gauss points and re-equilibrated with no time increment (:mod:`soilwater.efg.rebuild`).
With ``"paper"`` (the paper's scheme) it lives on the nodes: at the start of a step the
integration points of cells rebuilt on the current nodes take stress and state from the
nodes by MLS interpolation, and after a converged step the nodes update their own state
with the nodal stretching ``D^I`` (the one that enters ERR, paper eq. 1); that carried
state is not in equilibrium. With ``"nodal"``
the nodes are the integration points (stabilised conforming nodal integration,
:mod:`soilwater.efg.smoothing`) and keep the state their own equilibrium converged to;
their smoothing cells come from triangles that move with the nodes and are re-triangulated
when the worst falls below ``efg.rebuild_quality`` (nothing is carried: the state is on
the nodes). Every scheme moves the nodes by ``u^h(x_I)``.

Essential conditions act on total quantities, by penalty or by Nitsche's method
(``efg.essential``; :mod:`soilwater.efg.essential`): each boundary Gauss point keeps the gap
``u^h - u_bar`` of its constrained components, so reactions carried in earlier steps are not
lost (a velocity-controlled footing's uy target is -rate x t). A rigid plate (Mandel) or a
load-controlled footing adds one unknown, its settlement, tied to its points by the same
method; its total force equals the edge load or the footing's force. The reaction of each
named segment is the force of the condition over its points: ``-sum alpha w gap_y``
(penalty) or ``sum w (P n - beta gap)_y`` (Nitsche). When no boundary is drained or free and
the constituents are incompressible, the pore pressure is defined up to a constant: the mean
change of p_w over the domain is then pinned to zero by one Lagrange multiplier.

Here are the run (:func:`solve`), the step and what a run records. The step's
configuration is :mod:`soilwater.efg.discretisation`'s, its Newton system
:mod:`soilwater.efg.system`'s, the state kept between steps :mod:`soilwater.efg.model`'s.
"""

from dataclasses import replace
from functools import partial

import numpy as np
import scipy.sparse as sp

from soilwater.diagnostics.bifurcation import h1_gram, restricted_eigenvalue
from soilwater.efg.assembly import Pattern, scatter
from soilwater.efg.boundary import BOUNDARY_ORDER
from soilwater.efg.discretisation import background_cells, discretise, min_rcond
from soilwater.efg.essential.penalty import factors
from soilwater.efg.mls import ShapeFunctions
from soilwater.efg.model import Model, Points
from soilwater.efg.quadrature import lagrangian_cells, nodal_average
from soilwater.efg.rebuild import rebuild
from soilwater.efg.settings import check
from soilwater.efg.smoothing import nodal_cells
from soilwater.geometry.quality import cell_quality
from soilwater.geometry.triangulation import delaunay_triangles
from soilwater.efg.system import System
from soilwater.material.kinematics import invariants
from soilwater.nonlinear.gravity_start import switch_on
from soilwater.nonlinear.history import history_row, timed
from soilwater.nonlinear.march import run
from soilwater.nonlinear.newton import newton
from soilwater.physics.geostatic import initial_state
from soilwater.fields import permeability
from soilwater.results import Snapshot


def solve(case, progress=True):
    """Run a coupled case with EFG and return its :class:`~soilwater.results.Result`.

    Parameters
    ----------
    case : Case
        ``analysis = "coupled"``; Cam-clay or linear elastic skeleton.
    progress : bool
        Show a progress bar on the terminal.

    Raises
    ------
    ConvergenceError
        A step that still fails after ``MAX_CUTS`` halvings (the message names the time).
    InputError
        Bad supports (too small a scale factor), settings no scheme can take
        (:func:`soilwater.efg.settings.check`) and other invalid settings.
    """
    check(case.efg)
    model, start, gravity = _start(Model.build(case), progress)
    result = run(case, "efg", case.efg.to_dict(), start,
                 partial(_step, model), partial(_history_row, model),
                 partial(_snapshot, model),
                 {"dofs": 3 * len(case.nodes()), "stabilisation_beta": model.beta,
                  "stabilisation_tau": model.tau,
                  **factors(model, case.times()), **gravity}, progress)
    if model.gauss:
        records = result.summary.setdefault("rebuild_records", [])
        result.summary["rebuilds"] = len(records)
    return result


def _start(model, progress):
    """The model, its points at t = 0 and the summary's entries of the start: the case's
    initial points, or after a gravity start
    (:func:`soilwater.nonlinear.gravity_start.switch_on`) the phase's end with p_w = 0,
    no plate settlement, no stretching and no rebuilds counted, its gaps (the supports'
    reactions) kept, and the displacements measured from there (``origin``,
    ``probes0``); ``gravity_start`` (the phase's summary and its largest displacement
    [m]) in the summary."""
    start = _initial_points(model)
    case = model.case
    if case.initial.stress != "gravity":
        return model, start, {}
    end, phase = switch_on(model, _initial_points, _step, progress,
                           f"gravity efg {case.name}")
    settled = replace(end, p=start.p, plate=0.0, stretching=np.zeros_like(end.stretching),
                      cells=end.cells._replace(rebuilds=()))
    moved = np.linalg.norm(end.nodes - model.origin, axis=1).max()
    return (replace(model, origin=end.nodes.copy(), probes0=end.probes.copy()), settled,
            {"gravity_start": {**phase, "largest_displacement": float(moved)}})


def _initial_points(model):
    case = model.case
    nodes = case.nodes()
    cells = _cells(model, nodes) if model.consistent else None
    material_points = nodes if cells is None else cells.points
    stress, state = initial_state(case, model.material, material_points)
    n_bp = len(model.loop) * BOUNDARY_ORDER
    boundary = (None, None)
    if model.consistent and case.efg.essential == "nitsche":
        boundary = initial_state(case, model.material, model.initial_bp)
    return Points(nodes=nodes, stress=stress, state=state,
                  boundary_stress=boundary[0], boundary_state=boundary[1],
                  p=np.full(len(nodes), float(case.initial_pore_pressure)),
                  gap=np.zeros((n_bp, 2)), plate=0.0, plate_gap=np.zeros(n_bp),
                  probes=np.array([p.point for p in case.probes]).reshape(-1, 2),
                  stretching=np.zeros((len(material_points), 4)),
                  reactions=np.zeros(len(case.boundary.segments())), cells=cells)


def _cells(model, nodes, previous=None):
    """The next step's cells on ``nodes``: the triangles of the ``previous`` cells
    (``gauss``: the same material points, with their rebuild records; ``nodal``: their
    smoothing cells; the initial triangles by default), for ``nodal`` new triangles where
    one of those is worse than ``efg.rebuild_quality`` or turned over, or new background
    cells (``paper``). The rebuild of ``gauss`` is :func:`soilwater.efg.rebuild.rebuild`'s,
    after the step."""
    s = model.case.efg
    if not model.consistent:
        return background_cells(model, nodes)
    triangles = model.triangles if previous is None else previous.triangles
    if model.gauss:
        cells = lagrangian_cells(nodes, triangles, s.order)
        return cells if previous is None else cells._replace(rebuilds=previous.rebuilds)
    if cell_quality(nodes[triangles])[1].min() < s.rebuild_quality:
        triangles, _ = delaunay_triangles(nodes, nodes[model.loop])
    return nodal_cells(nodes, triangles)


def _step(model, points, t0, t1, stats, load=None):
    """One step on the configuration of ``points``: new points, iterations, residual.

    The new points carry the background cells of their own configuration, on which the
    next step integrates (and its history row measures them), and the smallest rcond of
    this step's MLS moment matrices (:func:`soilwater.efg.discretisation.min_rcond`).
    With ``gauss``, cells due for it are then rebuilt (:func:`soilwater.efg.rebuild.rebuild`);
    the iterations count the re-equilibration's."""
    disc = discretise(model, points.nodes, np.vstack([points.nodes, points.probes]),
                       stats["timings"], points.cells)
    system = System(model, points, disc, t0, t1, stats["timings"], load)
    iterations, residual = newton(system, stats)
    done = system.finish()
    with timed(stats["timings"], "cells_s"):
        done.cells = _cells(model, done.nodes, points.cells)
    done.rcond = min_rcond(disc)
    if model.case.diagnostics.uniqueness:
        done.uniqueness = _uniqueness(model, disc, system.domain_tangent(), system.n)
    if model.gauss:
        done, more = rebuild(model, done, t1, stats, load)
        iterations += more
    return done, iterations, residual


def _uniqueness(model, disc, K, n):
    """:func:`soilwater.diagnostics.bifurcation.restricted_eigenvalue` of a step's converged
    tangent over the initial P-wave modulus: the displacement block (penalties included) on
    the undrained constraint (the pressure rows), against the H1 Gram matrix of the trial
    functions (length scale: the body's height)."""
    su = disc.su
    pattern = Pattern.build((su, su))
    G = pattern.matrix(scatter(pattern, su, su, h1_gram(disc.w, model.case.geometry.height)),
                       2, 2)
    K = sp.csr_matrix(K)
    value = restricted_eigenvalue(K[:2 * n, :2 * n], K[2 * n:3 * n, :2 * n], G)
    return value / model.scales.modulus


def _history_row(model, points, t, dt, info):
    """:func:`soilwater.nonlinear.history.history_row` of the nodes (equal weights).

    ``min_angle`` and ``min_quality`` are those of the background cells of the configuration
    at the end of the step, which :func:`_step` builds and keeps on the points, so the next
    step integrates on the very cells measured here (no cells are built twice); square cells
    stay squares (90 degrees, quality 1, quarter cells included). ``min_rcond`` is the
    step's (:func:`soilwater.efg.discretisation.min_rcond`; of the last substep of a level
    that was cut back). With ``gauss``, ``rebuilds``: the cells' rebuilds so far (their
    records are the summary's ``rebuild_records``); after a rebuild the cells measured
    are the new ones."""
    case = model.case
    nodes0 = model.origin
    level = case.nodes()[:, 1] >= case.geometry.height * (1 - 1e-9)   # the top: facets
    top = model.loop[level[model.loop] & level[np.roll(model.loop, -1)]]   # at its height
    probes = ()
    if len(points.probes):
        s = case.efg
        shape = ShapeFunctions.build(points.nodes, points.probes, s.weight_p, s.scale_p,
                                     key="efg.scale_p")
        probes = zip([pr.name for pr in case.probes], shape.phi @ points.p,
                     points.probes - model.probes0)
    uniqueness = points.uniqueness if case.diagnostics.uniqueness else None
    segments = [(seg, points.nodes[k], nodes0[k], force,
                 points.plate if seg.load_controlled else None)
                for (_, seg), k, force in zip(case.boundary.segments(), case.segment_nodes(),
                                              points.reactions)]
    weights = points.cells.weights if model.consistent else None
    row = history_row(case, t, dt, info, points.stress, points.stretching,
                      points.nodes[top], nodes0[top], weights=weights, probes=probes,
                      uniqueness=uniqueness, segments=segments, cells=points.cells.cells,
                      rcond=points.rcond)
    if model.gauss:
        row["rebuilds"] = len(points.cells.rebuilds)
    return row


def _snapshot(model, points, t):
    s = model.case.efg
    at = ShapeFunctions.build(points.nodes, points.nodes, s.weight_p, s.scale_p,
                              key="efg.scale_p")
    stress, stretching, state = points.stress, points.stretching, points.state
    if model.gauss:                     # the Gauss-point state, projected for output
        n = len(points.nodes)
        stress, stretching = (nodal_average(points.cells, n, f) for f in (stress, stretching))
        state = {k: nodal_average(points.cells, n, v) for k, v in state.items()}
    p, q = invariants(stress)
    data = {"u": points.nodes - model.origin, "p_w": at.phi @ points.p,
            "p_eff": p, "q": q, "stress": stress, "stretching": stretching,
            "support_radius": at.support}
    data.update(state)
    data.update(permeability(model.case, state))
    cells = [("triangle", points.cells.triangles)] if model.consistent else []
    return Snapshot(t, points.nodes.copy(), data, cells)
