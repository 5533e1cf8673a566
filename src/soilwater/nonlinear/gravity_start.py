"""The gravity start (``initial.stress = "gravity"``): the self-weight switched on, drained,
before t = 0, by the method that then runs the case.

A geostatic start (:mod:`soilwater.physics.geostatic`) integrates sigma'_v down from a
level top; a slope has none. The gravity start is the gravity-loading phase of the
commercial codes instead, and works on any geometry:

1. From the uniform state (the material's p'0, e0 and ocr everywhere, its total stress
   ``-p'0 I`` the load of every free boundary as under a uniform start) the buoyant
   weight ``gamma'`` (:func:`soilwater.physics.geostatic.buoyant_weight`) is switched on
   in ``n = initial.increments`` equal steps, then held for one more. Each is a step of
   the solver's own scheme (same nodes, cells, integration points, essential
   conditions, finite strain, the material's return mapping) under the weight of ``g
   min(k / n, 1)`` at its end, k = 1 ... n + 1 (a step that fails is halved as in
   :func:`soilwater.nonlinear.march.march`, whose progress shows k as the time). The
   last step re-equilibrates the full weight: a dead load on the start-of-step
   configuration, it has then acted on the configuration the run starts from. Without
   it, the specific volume (updated with the exponential of the midpoint volumetric
   strain, which differs from J at second order in the step's strain) leaves the
   weight slightly out of balance there: the unloaded Cam-clay column of the tests
   then moved by 5e-6 of its 1.42 m settlement under gravity, and by 1e-8 with it.
   The phase is drained: its fluid has no coupling (Biot alpha = 0) and a storage
   ``1 / M`` (M the run's P-wave modulus scale), so the pore pressure stays at zero
   and the skeleton alone carries its weight. Nothing else moves or loads the
   soil: no velocity gradient (prescribed displacements hold still), the load factor
   0 (no edge tractions, no footing force), and footings are free, to be placed at
   t = 0 (:func:`drained`).
2. The coupled run then starts from the phase's end, point by point (the state lives
   where it did): effective stress, material state (Cam-clay's p'c and specific
   volume), the configuration, the carried boundary gaps (the reactions of the
   supports). The excess pore pressure is 0, the displacements are 0 and the last
   stretching is 0; the footings, edge tractions and velocity gradient act from
   t = 0+, as they would from a uniform start.

The geometry at t = 0 is the configuration deformed by gravity, and the displacements
are measured from it: the user's mesh is the ground before its own weight, and the
summary's ``gravity_start`` records how far the phase moved it. That is the only
configuration the state is in equilibrium on: finite-strain equilibrium ``div sigma +
gamma' = 0`` holds on the deformed configuration, and the weight of each point is that
of its solids over its current volume (``gamma' v`` is conserved). Put back on the
undeformed mesh, the stresses would be out of balance by the order of the phase's
strains, and the soil would weigh ``v_0 / v`` times what it does (a 15 % volume loss
of a soft clay under its weight would add 15 % of weight that was never applied): the
first coupled step would consolidate under that imbalance. Kept where it is, the state
is in equilibrium to the phase's Newton tolerance, and a run with no load stays still.

The horizontal stress is what the body's own deformation under its boundary conditions
gives (its own k0: ``nu / (1 - nu)`` for a linear elastic column under lateral
confinement, the normally consolidated ratio for Cam-clay that yields), not an input.
"""

import time
from dataclasses import replace

from soilwater.errors import ConvergenceError
from soilwater.nonlinear.history import TIMERS
from soilwater.nonlinear.march import march
from soilwater.nonlinear.newton import new_counts


def switch_on(model, initial, step, progress=True, desc=""):
    """March the gravity phase of ``model.case`` with a solver's own state and step.

    Parameters
    ----------
    model : object
        The solver's model of the case (a dataclass with ``case`` and ``scales``); the
        phase runs on copies whose ``case`` is the phase's (:func:`drained`).
    initial : callable
        ``initial(model) -> state``: the solver's state at the start (the uniform one).
    step : callable
        ``step(model, current, k0, k1, stats, load) -> (current, iterations,
        residual)``: the solver's step, k the increment.
    progress : bool
        Show the phase's progress (:class:`soilwater.nonlinear.progress.Progress`).
    desc : str
        What runs, for the progress.

    Returns
    -------
    state : object
        The solver's state at the end of the phase (full weight, drained).
    summary : dict
        ``increments``, ``newton_iterations``, ``cutbacks`` and ``time_s`` [s] of the
        phase.

    Raises
    ------
    ConvergenceError
        A step of the phase that still fails after every halving (the message gives
        the increment).
    """
    case = model.case
    phase = drained(case, model.scales.modulus)
    stats = {**new_counts(), "timings": dict.fromkeys(TIMERS, 0.0)}
    end = {}

    n = case.initial.increments

    def advance(current, k0, k1, load):
        weight = replace(case.gravity, g=case.gravity.g * min(k1 / n, 1.0))
        return step(replace(model, case=replace(phase, gravity=weight)), current, k0, k1,
                    stats, load)

    def row(current, s, ds, info):
        end["state"] = current
        return info

    tic = time.perf_counter()
    try:
        march(phase, initial(replace(model, case=phase)), advance, row,
              lambda current, s: None, stats, progress, desc)
    except ConvergenceError as err:
        raise ConvergenceError(f"initial.stress = \"gravity\": {err} (the times are "
                               f"the increments of the self-weight, {n} to switch it on; "
                               "more initial.increments may help)") from None
    return end["state"], {"increments": case.initial.increments,
                          "newton_iterations": stats["newton_iterations"],
                          "cutbacks": stats["cutbacks"],
                          "time_s": time.perf_counter() - tic}


def drained(case, modulus):
    """The case of the gravity phase: drained, unloaded, its footings free, the time the
    increment of the weight.

    Parameters
    ----------
    case : Case
        A case with a gravity start.
    modulus : float
        The run's P-wave modulus scale M [kPa]
        (:attr:`soilwater.physics.scales.Scales.modulus`).

    Returns
    -------
    Case
        The case with Biot alpha 0 and storage ``1 / M`` (the pore pressure, decoupled,
        stays 0), a uniform start, no velocity gradient and load factor 0, footings
        free, ``initial.increments + 1`` steps of one second, no diagnostics. Built
        with :func:`dataclasses.replace`: it is no case a user could load (alpha 0
        under gravity), only the phase's.
    """
    footings_free = tuple(
        (name, replace(edge, segments=tuple(
            replace(seg, ux="free", uy="free", settlement_rate=None, force=None)
            if seg.footing else seg for seg in edge.segments)))
        for name, edge in case.boundary.items())
    steps = case.initial.increments + 1
    return replace(case, fluid=replace(case.fluid, biot_alpha=0.0, storage=1.0 / modulus),
                   initial=replace(case.initial, stress="uniform"),
                   loading=replace(case.loading, velocity_gradient=((0.0, 0.0), (0.0, 0.0)),
                                   load=0.0),
                   time=replace(case.time, end=float(steps), steps=steps, dt0=None,
                                growth=None, dt_max=None, output=None, on_failure="error"),
                   boundary=replace(case.boundary, edges=footings_free),
                   diagnostics=replace(case.diagnostics, uniqueness=False))
