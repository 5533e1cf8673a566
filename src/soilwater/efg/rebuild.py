"""Rebuilding the Lagrangian cells of ``efg.integration = "gauss"``: new triangles, the
state carried to their Gauss points, and a re-equilibration.

The material state of ``gauss`` lives at the Gauss points of triangles of the nodes that
move with them. After a converged step whose worst triangle has a
:func:`soilwater.geometry.quality.cell_quality` below ``efg.rebuild_quality`` (the
threshold of ``nodal``), :func:`rebuild`

1. re-triangulates the current nodes: the Delaunay triangles inside the current boundary
   polygon (:func:`soilwater.geometry.triangulation.delaunay_triangles`, the gap behind a
   boundary edge that is no Delaunay edge closed by
   :func:`~soilwater.geometry.triangulation.close_boundary`). Nothing is rebuilt when they
   are the current triangles, or when they do not tile the polygon
   (:func:`~soilwater.geometry.triangulation.conforms`: a hole would lose material); the
   next step tries again;
2. carries the effective stress, the last stretching and every entry of the material state
   with the FEM re-meshing's transfer (:func:`soilwater.fem.transfer.transfer`): a triangle
   the two triangulations share keeps its Gauss-point values; the others take the L2
   projection of each quantity onto the continuous piecewise-linear functions of the old
   triangles, limited to the range at the Gauss points around each node, interpolated at
   their Gauss points. The state is then made admissible
   (:meth:`soilwater.material.protocol.Material.admissible`: Cam-clay's p'c raised to the
   yield surface through a carried stress outside it);
3. re-equilibrates: Newton's method on the step's equations with no time increment
   (``dt = 0``: the boundary data of the step's end, no flow, the undrained constraint on
   the increment) from the carried state on the new triangles. The state carried into the
   next step then satisfies equilibrium on the cells it is integrated on, as after any
   step; the nodes move by the small re-equilibration increment.

Each rebuild leaves a record (:func:`record`) on the new cells
(:attr:`soilwater.efg.quadrature.Quadrature.rebuilds`), which the cells of every later step
inherit, and in the run's statistics (``rebuild_records``): the history counts the
rebuilds, the summary lists their records.
"""

from dataclasses import replace

import numpy as np
from skfem import CellBasis, ElementTriP1, MeshTri

from soilwater.efg.discretisation import discretise
from soilwater.efg.quadrature import lagrangian_cells
from soilwater.efg.system import System
from soilwater.fem.transfer import transfer
from soilwater.geometry.quality import cell_quality
from soilwater.geometry.triangulation import close_boundary, conforms, delaunay_triangles
from soilwater.nonlinear.history import timed
from soilwater.nonlinear.newton import newton

#: The entries of a rebuild's record (the run summary's ``rebuild_records``).
RECORD = ("time", "quality_before", "quality_after", "out_of_balance_before",
          "out_of_balance_after", "iterations", "kept")


def due(model, cells):
    """Whether the worst of ``cells`` (a :class:`soilwater.efg.quadrature.Quadrature` of
    triangles) is below ``efg.rebuild_quality``."""
    return cell_quality(cells.cells)[1].min() < model.case.efg.rebuild_quality


def rebuild(model, points, t, stats, load=None):
    """``points`` on new triangles, carried and re-equilibrated (module docstring), when
    their cells are :func:`due` for it; else ``points`` unchanged.

    Parameters
    ----------
    model : soilwater.efg.model.Model
    points : soilwater.efg.model.Points
        Converged at time ``t`` [s], with the Lagrangian cells of their nodes (``cells``).
    t : float
        Time of ``points`` [s]: the boundary data the re-equilibration holds.
    stats : dict
        The step's statistics (:func:`soilwater.nonlinear.newton.newton`'s), added to;
        a rebuild appends its :func:`record` to ``stats["rebuild_records"]``.
    load : float, optional
        The load factor at ``t`` if not the case's (:func:`soilwater.nonlinear.march.march`).

    Returns
    -------
    points : soilwater.efg.model.Points
    iterations : int
        Newton's residual evaluations of the re-equilibration (0 without a rebuild).

    Raises
    ------
    ConvergenceError
        A carried stress no material state admits, or a re-equilibration that fails:
        the step is then cut back like any failing step.
    """
    old = points.cells
    if not due(model, old):
        return points, 0
    nodes, order = points.nodes, model.case.efg.order
    with timed(stats["timings"], "cells_s"):
        triangles, _ = delaunay_triangles(nodes, nodes[model.loop])
        triangles = close_boundary(triangles, model.loop, nodes)
        triangles, kept = aligned(triangles, old.triangles)
        if kept == len(triangles) == len(old.triangles) or not conforms(
                triangles, model.loop, len(nodes)):
            return points, 0
        new = lagrangian_cells(nodes, triangles, order)
    with timed(stats["timings"], "material_s"):
        stress, stretching, state = carried(model, old, new, points)
    start = replace(points, stress=stress, state=state, stretching=stretching, cells=new)
    disc = discretise(model, nodes, np.vstack([nodes, points.probes]), stats["timings"],
                      new)
    system = System(model, start, disc, t, t, stats["timings"], load)
    _, before = system.residual()
    iterations, after = newton(system, stats)
    done = system.finish()
    done.rcond, done.uniqueness = points.rcond, points.uniqueness
    with timed(stats["timings"], "cells_s"):
        cells = lagrangian_cells(done.nodes, triangles, order)
    entry = record(t, old, cells, before, after, iterations, kept / len(triangles))
    done.cells = cells._replace(rebuilds=old.rebuilds + (entry,))
    stats.setdefault("rebuild_records", []).append(entry)
    return done, iterations


def record(t, old, new, before, after, iterations, kept):
    """One rebuild's record (the entries :data:`RECORD`).

    Parameters
    ----------
    t : float
        Time of the rebuild [s].
    old, new : soilwater.efg.quadrature.Quadrature
        The cells before the rebuild and after the re-equilibration.
    before, after : float
        The scaled out-of-balance (:meth:`soilwater.efg.system.System.residual`, in the
        units of the Newton tolerance's scales) of the carried state on the new cells and
        after the re-equilibration.
    iterations : int
        Residual evaluations of the re-equilibration.
    kept : float
        Fraction of the new triangles the old triangulation had (their state kept).
    """
    return dict(zip(RECORD, (float(t), float(cell_quality(old.cells)[1].min()),
                             float(cell_quality(new.cells)[1].min()), float(before),
                             float(after), int(iterations), float(kept))))


def carried(model, old, new, points):
    """The effective stress (M, 4), stretching (M, 4) and material state at the Gauss
    points of the ``new`` cells, from those of ``old`` (``points``'), both on the nodes
    ``points.nodes``: :func:`soilwater.fem.transfer.transfer`, the state then made
    admissible."""
    names = list(points.state)
    values = np.column_stack([points.stress, points.stretching,
                              *(points.state[k] for k in names)])
    order = model.case.efg.order
    values = transfer(_basis(points.nodes, old.triangles, order),
                      _basis(points.nodes, new.triangles, order), values)
    stress = values[:, :4]
    state = model.material.admissible(stress, dict(zip(names, values[:, 8:].T)))
    return stress, values[:, 4:8], state


def aligned(triangles, old):
    """``triangles`` with each one ``old`` has too (the same three nodes) in ``old``'s
    vertex order, so its Gauss points are the same points; and how many there are.

    Examples
    --------
    >>> aligned(np.array([[1, 2, 0], [2, 3, 0]]), np.array([[0, 1, 2], [0, 1, 3]]))
    (array([[0, 1, 2],
           [2, 3, 0]]), 1)
    """
    n = max(triangles.max(), old.max()) + 1
    keys = [np.ravel_multi_index(np.sort(t, axis=1).T, (n, n, n)) for t in (triangles, old)]
    _, new_rows, old_rows = np.intersect1d(*keys, return_indices=True)
    triangles = triangles.copy()
    triangles[new_rows] = old[old_rows]
    return triangles, len(new_rows)


def _basis(nodes, triangles, order):
    """The P1 basis of ``triangles`` on ``nodes``, its vertex order kept, with the Gauss
    rule of :func:`soilwater.efg.quadrature.lagrangian_cells` (the same points, element-major,
    as its Gauss points)."""
    mesh = MeshTri(np.ascontiguousarray(nodes.T), np.ascontiguousarray(triangles.T),
                   sort_t=False)
    return CellBasis(mesh, ElementTriP1(), intorder=order)
