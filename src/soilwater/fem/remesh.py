"""Re-meshing of the FEM reference (``fem.remesh = "delaunay"``, triangle pairs).

:func:`remesh` re-triangulates the current vertices after a step whose worst element is
below ``fem.remesh_quality`` and carries the state to the new mesh
(:func:`soilwater.fem.transfer.transfer`); :func:`imbalance` measures the equilibrium
residual the carried stress leaves (see :mod:`soilwater.fem.solver`).
"""

from dataclasses import replace

import numpy as np

from soilwater.errors import ConvergenceError
from soilwater.fem.spaces import cell_bases, vertex_interpolant
from soilwater.fem.system import discretise, domain_residual, scaled_norm
from soilwater.fem.transfer import transfer
from soilwater.geometry.quality import cell_quality
from soilwater.geometry.triangulation import close_boundary, conforms, delaunay_triangles
from soilwater.nonlinear.history import timed


def remesh(model, current, t, timings, load=None):
    """``current`` on the Delaunay triangles of its vertices when ``fem.remesh`` asks for
    it and its worst element's quality is below ``fem.remesh_quality`` (module
    docstring); unchanged when those triangles are the mesh's own, and only counted
    (``refused``) when they do not tile the boundary polygon or the carried state
    cannot be made admissible.

    The state is carried (:func:`soilwater.fem.transfer.transfer`) and made admissible;
    the vertices, pore pressures and vertex velocities stay. ``remesh_residual`` is the
    scaled equilibrium residual of the new state at ``t`` under the load factor ``load``
    (the case's at t if None; :func:`imbalance`).
    """
    settings, space, vertices = model.case.fem, current.topology.space, current.vertices
    if settings.remesh == "never":
        return current
    with timed(timings, "cells_s"):
        if cell_quality(vertices[space.corners])[1].min() >= settings.remesh_quality:
            return current
        triangles, _ = delaunay_triangles(vertices, vertices[model.loop])
        triangles = close_boundary(triangles, model.loop, vertices)
        if _same_triangles(triangles, space.corners):
            return current
        if not conforms(triangles, model.loop, len(vertices)):
            return replace(current, refused=current.refused + 1)
    with timed(timings, "shape_functions_s"):
        _, old = cell_bases(space.moved(vertices), space.pair)
        topology = current.topology.remeshed(model.case, vertices, triangles)
        ub, pb = cell_bases(topology.space.moved(vertices), space.pair)
    with timed(timings, "material_s"):
        names = list(current.state)
        carried = transfer(old, pb, np.column_stack(
            [current.stress, current.stretching, *(current.state[k] for k in names)]))
        stress = carried[:, :4]
        try:
            state = model.material.admissible(stress, dict(zip(names, carried[:, 8:].T)))
        except ConvergenceError:
            return replace(current, refused=current.refused + 1)
    velocity = current.velocity.reshape(2, -1)[:, :len(vertices)].T
    new = replace(current, stress=stress, state=state, weights=ub.dx.ravel(),
                  stretching=carried[:, 4:8], topology=topology,
                  velocity=vertex_interpolant(ub, topology.space.mesh0.facets,
                                              velocity).T.ravel(),
                  remeshes=current.remeshes + 1)
    new.remesh_residual = imbalance(model, new, t, timings, load)
    return new


def _same_triangles(triangles, corners):
    """Whether two (E, 3) arrays of vertex indices hold the same triangles."""
    return len(triangles) == len(corners) and np.array_equal(
        np.unique(np.sort(triangles, axis=1), axis=0), np.unique(np.sort(corners, axis=1),
                                                                 axis=0))


def imbalance(model, current, t, timings, load=None):
    """The scaled residual (:func:`scaled_norm`, in units of the Newton tolerance's scales)
    of the state ``current`` on its own mesh at time t with no increment: the equilibrium
    imbalance of its stress (the continuity rows vanish with no increment and dt = 0)."""
    topology = current.topology
    disc = discretise(model, topology, current.vertices, t, timings, load)
    con, n = topology.constraints, len(current.stress)
    x = np.concatenate([np.zeros(2 * disc.u.n), current.p])
    R, _ = domain_residual(model, disc, current, x, current.stress, np.ones(n),
                     np.broadcast_to(np.eye(2), (n, 2, 2)), 0.0)
    reduced = con.T.T @ R
    if len(con.plate):
        reduced[-1] -= model.case.plate_force(t, load)
    return scaled_norm(reduced, con, model.scales.force, model.scales.volume, 0.0)
