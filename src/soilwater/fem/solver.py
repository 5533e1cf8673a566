"""Updated-Lagrangian u-p FEM (scikit-fem): the reference for the EFG solver.

The same scheme as ``soilwater/efg/solver.py``, with finite elements. A step from t_n to
t_(n+1) is solved on the mesh at x_n (bases rebuilt there) for the displacement increment
``du`` and ``p_w`` at t_(n+1). Its integrand and consistent tangent are
:mod:`soilwater.physics.weakform`'s (equilibrium with ``J sigma F^-T`` on x_n,
backward-Euler continuity), at the quadrature points, which are the material points (their
state needs no remapping); the stress is the material's return mapping with the midpoint
strain increment and the Hughes-Winget spin
(:func:`soilwater.nonlinear.newton.material_update`). The external load is the initial total
stress ``sigma0 . n`` on every boundary facet (sigma0 at the facet point's initial position,
:func:`soilwater.physics.geostatic.total_stress`: uniform or geostatic) plus the edge
traction x load factor on free components (a dead load on the start-of-step facets), and
under gravity the buoyant weight of the elements (:mod:`soilwater.physics.geostatic`). The
initial state is set at the quadrature points' initial positions; a gravity start then
loads it with its weight, drained, by this solver's own steps
(:mod:`soilwater.nonlinear.gravity_start`), and the run starts where that left the
quadrature points and the mesh.

Newton's method (:func:`soilwater.nonlinear.newton.newton`) starts from the last step's
velocity x dt (``L x`` at the first step). Convergence, cut-back and scales are those of
:mod:`soilwater.nonlinear.newton`, :mod:`soilwater.nonlinear.march` and
:mod:`soilwater.physics.scales`, shared with the EFG solver; a failing step (no
convergence, an element with ``J <= 0``, a material failure) is halved up to
:data:`soilwater.nonlinear.march.MAX_CUTS` times before the run stops with one error naming
the step time.

Essential conditions are exact: fixed and prescribed displacement DOFs (``(exp(L dt) - I)
x_n`` at the DOF's current position) and drained pressure DOFs (p_w = 0) are eliminated, and
so are the uy DOFs of a velocity-controlled footing (increment -rate x dt); a rigid plate
(or a load-controlled footing) ties every uy DOF of its edge (segment) to one unknown whose
equation is the plate's total force; the reaction of a named segment is the residual summed
over its uy DOFs; a confined body with incompressible constituents and no drained edge gets
the mean-pressure pin of the EFG solver (one Lagrange multiplier).

``fem-p1p1-stab`` adds the flow-equation perturbation of Aguilar, Gaspar, Lisbona and
Rodrigo (2008), "Numerical stabilization of Biot's consolidation model by a perturbation
on the flow equation", Int. J. Numer. Meth. Engng 75, 1282-1300:
``- beta int grad(p - p_n) . grad(q) dOmega_n`` with their ``beta = h^2 / (4 M)``,
``M = lambda + 2 mu`` the P-wave modulus at the initial state [kPa] and h the smallest
nodal spacing [m]. Their model has alpha = 1 and no storage; we keep their beta for any
alpha and S (on the Terzaghi column, alpha = 0.6, S = 0.0625, ``alpha^2 h^2 / (4 M)``
leaves a 10 % first-step overshoot, ``h^2 / (4 M)`` 0.3 %).

Re-meshing (``fem.remesh = "delaunay"``, triangle pairs): after a converged step whose worst
element has a :func:`soilwater.geometry.quality.cell_quality` below ``fem.remesh_quality``,
the current vertices are re-triangulated
(:func:`soilwater.geometry.triangulation.delaunay_triangles` inside the current boundary
polygon). The vertices, so the vertex DOFs, their values and the boundary DOF sets, stay;
Taylor-Hood's midside DOFs are those of the new edges (a boundary edge keeps its own, the
boundary loop being kept), and its predictor there is the mean of the edge's ends. The state
at the quadrature points (effective stress, every entry of the material state, the last
stretching) is carried by :func:`soilwater.fem.transfer.transfer` (kept elements keep
theirs; new ones get the L2 projection onto the old mesh's vertex basis, limited to the
local range, interpolated at their points), then made admissible
(:meth:`soilwater.material.protocol.Material.admissible`: Cam-clay's p'c raised to put a
stress outside the yield surface on it). The carried stress is not in equilibrium on the new
mesh; the next step's Newton iteration absorbs the imbalance, whose size is recorded
(``remesh_residual``). Nothing changes when the Delaunay triangles are the mesh's own. A
boundary edge that is no Delaunay edge (at a thin concave corner, such as the footing's
edge) leaves a gap, closed by :func:`soilwater.geometry.triangulation.close_boundary` when
it is one triangle. When the triangles still do not tile the boundary polygon
(:func:`soilwater.geometry.triangulation.conforms`), or the carried state cannot be made
admissible (a p' <= 0, which no p'c mends), the old mesh is kept for that step and counted
(``remesh_refused``); the next step tries again. Probes are material points: at a re-meshing
their current position (the old mesh's interpolation of the vertex positions) is located in
the new mesh.

Linear solver: :mod:`soilwater.linalg.backends` (PARDISO when ``pypardiso`` is installed,
SuperLU otherwise) on the condensed, unsymmetric tangent, reused within a step (modified
Newton) while it contracts the residual at least tenfold per iteration. PARDISO keeps its
default ordering with weighted matching here, not the node-blocked ordering of the EFG
solver, under which the unstable P1/P1 pair needs more Newton iterations. Each pair
chooses how its tangents are solved (:func:`soilwater.fem.system.policy`).

Here are the run (:func:`solve`), the step and what a run records. The exact essential
conditions are :mod:`soilwater.fem.constraints`', the step's discretisation and Newton
system :mod:`soilwater.fem.system`'s, the re-meshing :mod:`soilwater.fem.remesh`'s, the
state kept between steps :mod:`soilwater.fem.model`'s.
"""

from dataclasses import replace
from functools import partial

import numpy as np

from soilwater.fem.constraints import Constraints
from soilwater.fem.model import Model, State, Topology
from soilwater.fem.remesh import remesh
from soilwater.fem.spaces import cell_bases
from soilwater.fem.system import System, discretise
from soilwater.material.kinematics import invariants
from soilwater.nonlinear.gravity_start import switch_on
from soilwater.nonlinear.history import history_row
from soilwater.nonlinear.march import run
from soilwater.nonlinear.newton import newton
from soilwater.physics.geostatic import initial_state
from soilwater.fields import permeability
from soilwater.results import Snapshot


def solve(case, method="fem-th", progress=True):
    """Run a coupled case with an FEM element pair and return its Result.

    Parameters
    ----------
    case : Case
        ``analysis = "coupled"``; Cam-clay or linear elastic skeleton.
    method : str
        One of :data:`soilwater.fem.spaces.PAIRS`.
    progress : bool
        Show a progress bar on the terminal.

    Raises
    ------
    ConvergenceError
        A step that still fails after ``MAX_CUTS`` halvings (the message names the time).
    InputError
        A static case, a quadrilateral method on a ``grid+centres`` case or with
        ``fem.remesh``.
    """
    model, start, gravity = _start(Model.build(case, method), progress)
    space = model.space
    pair = space.pair
    options = {"elements": f"{pair.u_element.__name__}/{pair.p_element.__name__}",
               "intorder": pair.intorder, "stabilised": pair.stabilised}
    result = run(case, method, options, start, partial(_step, model),
                 partial(_history_row, model), partial(_snapshot, model),
                 {"dofs": int(2 * space.n_u + space.n_p),
                  "elements": int(space.mesh0.t.shape[1]),
                  "stabilisation_beta": model.beta, **gravity}, progress)
    if case.fem.remesh != "never":
        last = result.history.iloc[-1]
        result.summary.update(remeshes=int(last["remeshes"]),
                              remesh_refused=int(last["remesh_refused"]))
    return result


def _start(model, progress):
    """The model, its state at t = 0 and the summary's entries of the start: the case's
    initial state, or after a gravity start
    (:func:`soilwater.nonlinear.gravity_start.switch_on`) the phase's end with the
    case's own constraints, p_w = 0, no stretching, the predictor ``L x`` and the
    displacements measured from there (``origin``); ``gravity_start`` (the phase's
    summary and its largest displacement [m]) in the summary."""
    start = _initial_state(model)
    case = model.case
    if case.initial.stress != "gravity":
        return model, start, {}
    end, phase = switch_on(model, _initial_state, _step, progress,
                           f"gravity {model.method} {case.name}")
    space = end.topology.space
    ub, _ = cell_bases(space.moved(end.vertices), space.pair)
    settled = replace(end, p=start.p, stretching=np.zeros_like(end.stretching),
                      velocity=(case.loading.L @ ub.doflocs).ravel(),
                      topology=replace(end.topology,
                                       constraints=Constraints.build(case, space)),
                      remeshes=0, refused=0, remesh_residual=0.0)
    moved = np.linalg.norm(end.vertices - model.origin, axis=1).max()
    return (replace(model, origin=end.vertices.copy()), settled,
            {"gravity_start": {**phase, "largest_displacement": float(moved)}})


def _initial_state(model):
    case, space = model.case, model.space
    ub, _ = cell_bases(space.mesh0, space.pair)
    n_points = ub.dx.size
    stress, state = initial_state(case, model.material,
                                  np.asarray(ub.global_coordinates()).reshape(2, -1).T)
    return State(vertices=case.nodes(), stress=stress, state=state,
                 p=np.full(space.n_p, float(case.initial_pore_pressure)),
                 weights=ub.dx.ravel(), stretching=np.zeros((n_points, 4)),
                 velocity=(case.loading.L @ ub.doflocs).ravel(),
                 topology=Topology.initial(case, space),
                 reactions=np.zeros(len(case.boundary.segments())))


def _step(model, current, t0, t1, stats, load=None):
    """One step on the mesh at ``current.vertices``, then the re-meshing if it is due:
    new state, iterations, residual."""
    disc = discretise(model, current.topology, current.vertices, t1, stats["timings"], load)
    system = System(model, current, disc, t0, t1, stats["timings"], load)
    iterations, residual = newton(system, stats)
    return remesh(model, system.finish(), t1, stats["timings"], load), iterations, residual


def _history_row(model, current, t, dt, info):
    """:func:`soilwater.nonlinear.history.history_row` of the quadrature points (weighted by
    volume); ``min_angle`` and ``min_quality`` of the elements on the moved mesh (their
    corner vertices: the straight-sided cell of a Taylor-Hood or Q2 element), the mesh the
    next step is solved on; with ``fem.remesh``, ``remeshes`` and ``remesh_refused`` (counts
    so far) and ``remesh_residual`` (:func:`soilwater.fem.remesh.imbalance` after the last
    re-meshing, 0 before the first; read it where ``remeshes`` grows)."""
    case, topology = model.case, current.topology
    top = model.space.mesh0.p[1] > case.geometry.height * (1 - 1e-9)
    probes = ()
    nodes0 = model.origin
    if topology.probes is not None:     # vertex displacements, linear between vertices
        moved = topology.probes @ (current.vertices - nodes0)
        probes = zip([pr.name for pr in case.probes], topology.probes @ current.p, moved)
    segments = [(seg, current.vertices[k], nodes0[k], force,
                 float(current.vertices[k[0], 1] - nodes0[k[0], 1])  # the plate's uy
                 if seg.load_controlled else None)
                for (_, seg), k, force in zip(case.boundary.segments(), case.segment_nodes(),
                                              current.reactions)]
    row = history_row(case, t, dt, info, current.stress, current.stretching,
                      current.vertices[top], nodes0[top],
                      current.weights / current.weights.sum(), probes,
                      current.uniqueness if case.diagnostics.uniqueness else None,
                      segments, cells=current.vertices[topology.space.corners])
    if case.fem.remesh != "never":
        row.update(remeshes=current.remeshes, remesh_refused=current.refused,
                   remesh_residual=current.remesh_residual)
    return row


def _snapshot(model, current, t):
    """Vertex fields with the current cells: u, p_w, the last step's velocity, and p', q,
    the effective stress and the state averaged to the vertices (each vertex: the
    volume-weighted mean of its elements' means); for the quadratic pairs also what the
    files need to write them on their own nodes (:func:`soilwater.fields.quadratic`)."""
    space = current.topology.space
    mesh0 = space.mesh0
    cells = mesh0.t
    E, N = cells.shape[1], len(current.vertices)
    p, q = invariants(current.stress)
    quantities = {"p_eff": p, "q": q, "stress": current.stress,
                  "stretching": current.stretching, **current.state}
    velocity = current.velocity.reshape(2, -1).T
    data = {"u": current.vertices - model.origin, "p_w": current.p[:N],
            "velocity": velocity[:N]}
    volume = current.weights.reshape(E, -1)
    share = np.repeat(volume.sum(1), cells.shape[0])
    node_volume = np.bincount(cells.T.ravel(), share, minlength=mesh0.p.shape[1])
    for name, values in quantities.items():
        mean = np.einsum("eq,eqk->ek", volume, values.reshape(*volume.shape, -1))
        total = np.column_stack([np.bincount(cells.T.ravel(), np.repeat(m, cells.shape[0]),
                                             minlength=N) for m in mean.T])
        data[name] = (total / node_volume[:, None]).reshape((N, *values.shape[1:]))
    data.update(permeability(model.case, data))
    quadratic = None
    if space.n_u > N:                   # the quadratic pairs' own nodes, for the files
        quadratic = {"facets": mesh0.facets.T.copy(), "t2f": mesh0.t2f.T.copy(),
                     "velocity": velocity}
    return Snapshot(t, current.vertices.copy(), data,
                    cells=[(space.cell_type, cells.T.copy())], quadratic=quadratic)
