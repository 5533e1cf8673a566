"""What a coupled run records: the phase timers and the columns of its history rows.

* :data:`TIMERS` and :func:`timed`: the wall time of a run's phases;
* :func:`history_row`: the columns of a history row, with :func:`segment_columns` per
  named boundary segment, :func:`axial_strain` and :func:`stretching_error`.
"""

import time
from contextlib import contextmanager

import numpy as np

from soilwater.case.boundary import traction_at
from soilwater.geometry.quality import cell_quality
from soilwater.material.kinematics import invariants

#: Phase timers of a run [s], ``summary["timings"]`` of both methods (plus ``total_s``):
#: background cells or mesh geometry, shape functions or bases, assembly of the tangent
#: (and of sparsity patterns), factorisations and back-solves, material updates.
TIMERS = ("cells_s", "shape_functions_s", "assembly_s", "solve_s", "material_s")


@contextmanager
def timed(timings, key):
    """Add the wall time of the ``with`` block to ``timings[key]`` [s]."""
    tic = time.perf_counter()
    yield
    timings[key] += time.perf_counter() - tic


def history_row(case, t, dt, info, stress, stretching, top, top0, weights=None, probes=(),
                uniqueness=None, segments=(), cells=None, rcond=None):
    """One row of a coupled run's history.

    Parameters
    ----------
    case : Case
    t, dt : float
        The level's time and step [s].
    info : dict
        ``iterations``, ``substeps``, ``residual`` and ``linear_iterations`` of the level
        (:func:`soilwater.nonlinear.march.march`); the Krylov iterations become a column
        where there were any.
    stress, stretching : ndarray, shape (P, 4)
        Effective stress (tension positive) and last stretching [1/s] at the material
        points.
    top, top0 : ndarray, shape (T, 2)
        Current and initial positions of the top edge's nodes [m].
    weights : ndarray, shape (P,), optional
        Weights of the domain averages (current volumes); equal weights by default.
    probes : iterable of (str, float, ndarray)
        Probe name, its pore pressure [kPa] and its displacement (2,) [m] (the probe moves
        with the soil).
    uniqueness : float, optional
        The :mod:`soilwater.diagnostics.bifurcation` indicator of the level, if asked for.
    segments : iterable of (Segment, ndarray, ndarray, float, float or None)
        Per named segment (:meth:`soilwater.case.boundary.Boundary.segments` order): the
        segment, the current and initial positions (K, 2) [m] of its boundary nodes, the
        vertical force the boundary exerts on the soil over it (reaction, per unit
        thickness, y up positive [kN/m]) and the plate unknown (uy [m]) of a load-controlled
        footing, else None.
    cells : ndarray, shape (C, V, 2), optional
        The current cells (FEM elements or EFG background cells), counter-clockwise in their
        undeformed state, V = 3 or 4 (:func:`soilwater.geometry.quality.cell_quality`).
    rcond : float, optional
        The smallest reciprocal condition number of the MLS moment matrix over the
        level's integration points (EFG).

    Returns
    -------
    dict
        ``time``, ``eps_a`` (:func:`axial_strain`), ``p`` and ``q`` (domain averages of p',
        q [kPa]), ``err`` (:func:`stretching_error`), ``gamma`` (mean horizontal
        displacement of the top over the height), ``settlement`` (mean downward displacement
        of the top edge's nodes [m]), ``dt``, ``iterations``, ``substeps``, ``residual``,
        ``p_w@NAME``, ``ux@NAME`` and ``uy@NAME`` [m] per probe, if given, ``uniqueness``
        and per segment ``settlement@NAME``
        and ``pressure@NAME`` (:func:`segment_columns`); with ``cells``, ``min_angle``
        [degrees] and ``min_quality`` (the worst cell's
        :func:`soilwater.geometry.quality.cell_quality`), with ``rcond``, ``min_rcond``.
    """
    p, q = invariants(stress)
    quality = {}
    if cells is not None:
        angle, shape = cell_quality(cells)
        quality = {"min_angle": float(angle.min()), "min_quality": float(shape.min())}
    if rcond is not None:
        quality["min_rcond"] = float(rcond)
    contact, load = {}, case.loading.factor(t)
    for seg, nodes, nodes0, reaction, plate in segments:
        contact.update(segment_columns(seg, t, nodes, nodes0, reaction, plate, load))
    return {"time": t, "eps_a": axial_strain(case, top[:, 1]),
            "p": np.average(p, weights=weights), "q": np.average(q, weights=weights),
            "err": stretching_error(case, stretching[:, 1], weights),
            "gamma": np.mean(top[:, 0] - top0[:, 0]) / case.geometry.height,
            "settlement": -float(np.mean(top[:, 1] - top0[:, 1])),
            "dt": dt, "iterations": info["iterations"], "substeps": info["substeps"],
            "residual": info["residual"], **_probe_columns(probes),
            **({"linear_iterations": info["linear_iterations"]}
               if info.get("linear_iterations") else {}),
            **({} if uniqueness is None else {"uniqueness": uniqueness}), **contact,
            **quality}


def segment_columns(segment, t, nodes, nodes0, reaction, plate=None, load=1.0):
    """``settlement@NAME`` [m, positive down] and ``pressure@NAME`` [kPa, compression
    positive] of one named segment at time t [s].

    The settlement is the footing's: ``settlement_rate x t`` under velocity control,
    ``-plate`` under load control; for a segment that is no footing, the mean downward
    displacement of its nodes. The pressure is the mean vertical pressure on the soil,
    ``-reaction / width``, the width being the current distance between the segment's two
    end nodes (those furthest apart along its longer initial extent; ``to - from`` with
    fewer than two nodes), plus, on a mesh group that carries a traction, the applied
    ``-ty`` times the load factor ``load``, mean over its nodes.

    Examples
    --------
    >>> from soilwater.case.boundary import Segment
    >>> seg = Segment("f", 0.0, 1.0, uy="footing", settlement_rate=1e-3)
    >>> nodes0 = np.array([[0.0, 1.0], [1.0, 1.0]])
    >>> cols = segment_columns(seg, 2.0, nodes0 + [[0.0, -2e-3], [0.1, -2e-3]], nodes0, -5.5)
    >>> round(cols["settlement@f"], 12), round(cols["pressure@f"], 12)
    (0.002, 5.0)
    """
    nodes, nodes0 = np.asarray(nodes).reshape(-1, 2), np.asarray(nodes0).reshape(-1, 2)
    if segment.load_controlled:
        settlement = -plate
    elif segment.footing:
        settlement = segment.settlement_rate * t
    else:
        settlement = -float(np.mean(nodes[:, 1] - nodes0[:, 1])) if len(nodes) else 0.0
    width = segment.end - segment.start
    if len(nodes0) > 1:
        order = np.argsort(nodes0[:, np.argmax(np.ptp(nodes0, axis=0))])
        width = np.linalg.norm(nodes[order[-1]] - nodes[order[0]])
    pressure = -reaction / width
    if segment.traction is not None:
        pressure -= load * float(np.mean(traction_at(segment.traction, nodes0)[:, 1]))
    return {f"settlement@{segment.name}": float(settlement),
            f"pressure@{segment.name}": float(pressure)}


def _probe_columns(probes):
    """``p_w@NAME``, ``ux@NAME``, ``uy@NAME`` of each ``(name, p_w, u)``."""
    columns = {}
    for name, p_w, u in probes:
        columns.update({f"p_w@{name}": float(p_w), f"ux@{name}": float(u[0]),
                        f"uy@{name}": float(u[1])})
    return columns


def axial_strain(case, heights):
    """``eps_a = -ln(h / H)``: logarithmic axial strain from current top heights [m]."""
    return float(-np.log(np.mean(heights) / case.geometry.height))


def stretching_error(case, d22, weights=None):
    """Paper eq. 1: mean over points of ``|(D22_exact - D22^I) / D22_exact|``.

    ``D22_exact`` is the case's prescribed ``L22``; NaN when it is zero (undefined).
    ``weights`` (e.g. quadrature volumes) turn the mean into a weighted one.
    """
    L22 = case.loading.L[1, 1]
    if L22 == 0:
        return np.nan
    return float(np.average(np.abs((L22 - d22) / L22), weights=weights))
