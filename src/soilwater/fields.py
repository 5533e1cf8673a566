"""The fields a result's VTU files hold: a snapshot made ready for a post-processor.

A :class:`~soilwater.results.Snapshot` keeps what a solver carries (vertex or node values,
the cells it has, or none for the paper's EFG); :func:`mesh` turns it into what ParaView
or pyvista can contour, warp and query:

* cells everywhere: the solver's own, or for a point cloud the Delaunay triangles of the
  initial nodes inside the initial boundary, carried to the current positions; the
  quadratic pairs (fem-th, fem-q2q1) as 6-node triangles or 9-node quadrilaterals on
  their own displacement nodes, where the last step's velocity is the solver's own
  quadratic field and every other field, like the straight-sided configuration the
  solver moves, is linear between the vertices;
* ``u`` with three components (z = 0), tensors with nine;
* the fields derived from the case: void ratio, permeability, total pore pressure, the
  total stress; and per cell the logarithmic strain and its shear invariant.

Units of every field are in :data:`UNITS` (kPa, m, s in the built-in cases; a case in
other units keeps its own), which ``summary.json`` repeats as ``field_units``. Signs:
stresses and strains tension positive, pressures (p_w, p', the totals) compression
positive.
"""

import meshio
import numpy as np

from soilwater.geometry.triangulation import delaunay_triangles
from soilwater.material.kinematics import IDENTITY, inverse
from soilwater.material.regions import fluid_at
from soilwater.physics.geostatic import G_N

#: Unit of every field written (``-``: dimensionless). Point data: ``u`` displacement;
#: ``p_w`` pore pressure in excess of hydrostatic, ``p_w_total`` with the hydrostatic
#: pressure of a water table at the initial top surface (equal without gravity);
#: ``p_eff`` and ``q`` the invariants of the effective stress; ``pc`` Cam-clay's
#: preconsolidation pressure; ``v`` specific volume, ``e`` void ratio; ``k`` hydraulic
#: conductivity; ``stress`` effective and ``stress_total`` total Cauchy stress (3 x 3);
#: ``stretching`` (3 x 3) and, for FEM, ``velocity`` of the last step;
#: ``support_radius`` EFG's MLS support. Cell data: ``log_strain`` the Hencky strain
#: ``ln V`` (3 x 3; ``F = V R``) of each cell from its corners' initial and current
#: positions, ``shear_strain`` its invariant ``sqrt(2/3 e:e)``, ``e`` its deviator;
#: with material regions, ``region`` (integer) the index into the case's region names
#: (``summary.json``'s ``regions``) of the region that holds the cell's initial centre.
UNITS = {"u": "m", "p_w": "kPa", "p_w_total": "kPa", "p_eff": "kPa", "q": "kPa",
         "pc": "kPa", "v": "-", "e": "-", "k": "m/s", "stress": "kPa",
         "stress_total": "kPa", "stretching": "1/s", "velocity": "m/s",
         "support_radius": "m", "log_strain": "-", "shear_strain": "-", "region": "-"}
#: Quadratic VTK cell of each linear one (the quadratic pairs' own nodes).
QUADRATIC = {"triangle": "triangle6", "quad": "quad9"}


def mesh(snapshot, case):
    """A snapshot as the :class:`meshio.Mesh` a result folder writes.

    Parameters
    ----------
    snapshot : soilwater.results.Snapshot
    case : Case
        The case solved: its boundary (the cells of a point cloud), gravity and fluid
        (total pore pressure, total stress, permeability).

    Returns
    -------
    meshio.Mesh
        Current positions (N, 3), z = 0; one cell block; the fields of :data:`UNITS`
        that the snapshot has or that follow from it. A point's material region (a
        smoothed value where solvers carry it) is written as the integer cell field
        ``region`` instead. Its ``field_data["TimeValue"]`` is the snapshot's time [s]
        (ParaView's name; a VTU file written by meshio drops it, and a result folder's
        ``fields.pvd`` gives each file's time).
    """
    points = np.asarray(snapshot.points)
    data = {k: v for k, v in snapshot.point_data.items() if k != "permeability"}  # -> k
    initial = points - data["u"]
    if snapshot.cells:
        (kind, cells), = snapshot.cells
    else:
        kind = "triangle"
        cells, _ = delaunay_triangles(initial, initial[case.boundary_loop()])
    corners = cells
    if snapshot.quadratic is not None:
        points, initial, data, cells = quadratic(points, initial, data, cells,
                                                 snapshot.quadratic)
        kind = QUADRATIC[kind]
    data = {**data, **derived(case, points, data)}
    cell_data = strains(initial[corners], points[corners])
    if data.pop("region", None) is not None:
        cell_data["region"] = case.geometry.region_of(initial[corners].mean(axis=1))
    data = {name: _vtk(values) for name, values in data.items()}
    points3 = np.column_stack([points, np.zeros(len(points))])
    return meshio.Mesh(points3, [(kind, cells)], point_data=data,
                       cell_data={k: [v] for k, v in cell_data.items()},
                       field_data={"TimeValue": np.array([float(snapshot.time)])})


def permeability(case, state):
    """``{"permeability": k}`` [m/s] at the points of ``state`` (its specific volumes
    ``v``, and ``region`` with material regions) when k varies (with the void ratio,
    ``material.permeability_law``, or by region), else ``{}``: the snapshot field."""
    fluid = case.fluid
    if "region" in state:
        fluid = fluid_at(fluid, case.material(), state)
    elif fluid.permeability_law == "constant":
        return {}
    return {"permeability": fluid.mobility_at(state["v"])[0] * fluid.gamma_w}


def derived(case, points, data):
    """Fields that follow from the solver's and the case's: ``e`` and ``k`` (of the law at
    that ``v``), ``p_w_total`` and ``stress_total`` (where the snapshot has ``v``,
    ``p_w``, ``stress``)."""
    out = {}
    fluid = case.fluid
    if "v" in data:
        out["e"] = data["v"] - 1.0
        out["k"] = permeability(case, data).get("permeability",
                                                np.full(len(points), fluid.permeability))
    if "p_w" not in data:               # a static (dry) analysis
        return out
    hydrostatic = (fluid.gamma_w * case.gravity.g / G_N
                   * (case.geometry.height - points[:, 1]))
    out["p_w_total"] = data["p_w"] + hydrostatic
    if "stress" in data:
        out["stress_total"] = (data["stress"] - fluid.biot_alpha * out["p_w_total"][:, None]
                               * IDENTITY)
    return out


def quadratic(points, initial, data, cells, extra):
    """The quadratic pairs' own nodes: vertices, then edge midpoints (and quadrilateral
    centres), with each field linear between the vertices except ``velocity``.

    ``extra`` holds ``facets`` (F, 2) vertex pairs, ``t2f`` (E, 3 or 4) each cell's
    facets in VTK's edge order, and ``velocity`` (n_u, 2) on scikit-fem's displacement
    DOFs (vertices, facets, then cell interiors), the order of the points returned.
    """
    facets, t2f = extra["facets"], extra["t2f"]
    n, centres = len(points), cells.shape[1] == 4

    def grow(values):
        values = np.asarray(values)
        parts = [values, values[facets].mean(axis=1)]
        if centres:
            parts.append(values[cells].mean(axis=1))
        return np.concatenate(parts)

    out = {name: grow(values) for name, values in data.items()}
    if extra.get("velocity") is not None and len(extra["velocity"]) == len(out["u"]):
        out["velocity"] = extra["velocity"]
    blocks = [cells, n + t2f]
    if centres:
        blocks.append(n + len(facets) + np.arange(len(cells))[:, None])
    return grow(points), grow(initial), out, np.hstack(blocks)


def strains(initial, current):
    """Per cell (C, 3 or 4 corners, 2): the Hencky strain ``ln V`` (C, 9) and its shear
    invariant ``sqrt(2/3 e:e)``, e its deviator; plane strain (no stretch along z).

    ``F`` is the cell's linear map from its corners' initial to current positions (for
    a quadrilateral, at its centre).

    Examples
    --------
    >>> square = np.array([[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]])
    >>> out = strains(square, square * [1.0, np.exp(-0.1)])      # 10 % log shortening
    >>> out["log_strain"][0, [0, 4, 8]].round(12).tolist()
    [0.0, -0.1, 0.0]
    >>> round(float(out["shear_strain"][0]), 6)   # sqrt(2/3) |e|, e = (1, -2, 1)/30
    0.066667
    """
    def edges(x):
        if x.shape[1] == 4:                 # bilinear map's tangents at the centre
            return np.stack([x[:, 1] + x[:, 2] - x[:, 0] - x[:, 3],
                             x[:, 2] + x[:, 3] - x[:, 0] - x[:, 1]], axis=2) / 2
        return np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=2)

    F = edges(current) @ inverse(edges(initial))
    values, vectors = np.linalg.eigh(F @ np.swapaxes(F, 1, 2))
    log2 = np.einsum("cij,cj,ckj->cik", vectors, 0.5 * np.log(values), vectors)
    log3 = np.zeros((len(F), 3, 3))
    log3[:, :2, :2] = log2
    deviator = log3 - np.trace(log3, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    shear = np.sqrt(2 / 3 * np.einsum("cij,cij->c", deviator, deviator))
    return {"log_strain": log3.reshape(-1, 9), "shear_strain": shear}


def _vtk(values):
    """A field as VTK wants it: vectors (N, 2) with a zero z, stress-like (N, 4) vectors
    ``[xx, yy, zz, xy]`` as full 3 x 3 tensors (N, 9)."""
    values = np.asarray(values, dtype=float)
    if values.ndim == 2 and values.shape[1] == 2:
        return np.column_stack([values, np.zeros(len(values))])
    if values.ndim == 2 and values.shape[1] == 4:
        xx, yy, zz, xy = values.T
        zero = np.zeros(len(values))
        return np.column_stack([xx, xy, zero, xy, yy, zero, zero, zero, zz])
    return values
