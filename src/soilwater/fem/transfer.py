"""Carrying quadrature-point fields from one mesh of the current vertices to another.

When the FEM reference re-meshes (``fem.remesh = "delaunay"``, :mod:`soilwater.fem.solver`)
the vertices stay where they are, so the displacement and pressure DOFs at the vertices
keep their values; what lives at the quadrature points (the effective stress, every entry
of the material state, the last stretching) must be carried to the new points. An element
the re-meshing keeps (the same three vertices) keeps its values: its quadrature points are
the same points. The new elements receive

1. **recovery**: the L2 projection of each quantity onto the continuous piecewise-linear
   functions of the old mesh (its vertex basis: the pressure basis of every triangle
   pair), ``M v = int N_i f`` with the consistent mass matrix ``M``, integrated with the
   old quadrature weights, each vertex value then **limited** to the range of the
   quantity at the quadrature points of the elements around the vertex (:func:`recover`);
2. **interpolation** of those vertex values with the new mesh's vertex basis at its
   quadrature points.

The projection reproduces a field linear in x (given a rule exact for quadratics, as every
pair's is) and keeps each quantity's integral over the domain (the basis sums to one).
It is not monotone: next to a steep change, such as the stress at the edge of a footing,
it overshoots, and unlimited it can carry p' < 0 to the footing's corner, a state no
Cam-clay p'c makes admissible. The limiter keeps every carried value within the range of
its neighbourhood, so a positive quantity (p'c, v) stays positive, and so does a stress
component that is compressive around the vertex (p', a sum of three components, is not
bounded by the range of p' itself); it leaves a linear
field exact at every vertex that lies inside the convex hull of its neighbourhood's
quadrature points (interior vertices), and caps it at a boundary vertex, where a linear
field's value lies beyond that range. The volume-weighted average of element means that
the VTU snapshots show (:func:`soilwater.fem.solver._snapshot`) is monotone too, but
exact for a linear field only at a vertex that is the area-weighted centroid of its
elements' centroids, and it smears a stress concentration more. The interpolation on the
new mesh keeps the integral only where the two meshes give the vertices the same share of
the area (``int N_i``).
"""

import numpy as np

from soilwater.fem.assembly import Shapes, block
from soilwater.linalg.backends import factorise
from soilwater.physics.weakform import Coefficients


def recover(shapes, dx, values):
    """Limited L2 projection of quadrature-point values onto the vertex basis.

    :func:`project`, each vertex value then clipped to the smallest and largest value
    of the quantity at the quadrature points of the elements that share the vertex.

    Parameters
    ----------
    shapes : soilwater.fem.assembly.Shapes
        The P1 (vertex) basis of the mesh the values live on.
    dx : ndarray, shape (E, Q)
        Quadrature weights of that mesh [m2].
    values : ndarray, shape (E Q, F)
        F quantities at the quadrature points (element-major).

    Returns
    -------
    ndarray, shape (n, F)
    """
    E, Q = dx.shape
    values = values.reshape(E, Q, -1)
    vertices = shapes.dofs.ravel()                          # (3 E,): a-major
    low = np.full((shapes.n, values.shape[2]), np.inf)
    high = np.full_like(low, -np.inf)
    np.minimum.at(low, vertices, np.tile(values.min(axis=1), (shapes.dofs.shape[0], 1)))
    np.maximum.at(high, vertices, np.tile(values.max(axis=1), (shapes.dofs.shape[0], 1)))
    return np.clip(project(shapes, dx, values.reshape(E * Q, -1)), low, high)


def project(shapes, dx, values):
    """L2 projection of quadrature-point values onto the vertex basis.

    Parameters
    ----------
    shapes : soilwater.fem.assembly.Shapes
        The P1 (vertex) basis of the mesh the values live on.
    dx : ndarray, shape (E, Q)
        Quadrature weights of that mesh [m2].
    values : ndarray, shape (E Q, F)
        F quantities at the quadrature points (element-major).

    Returns
    -------
    ndarray, shape (n, F)
        Vertex values ``v`` with ``M v = int N_i f`` for each quantity.
    """
    E, Q = dx.shape
    F = values.shape[1]
    mass = Coefficients.of({(0, 0, 0, 0): dx.ravel()}, (1, 1))
    lu = factorise(block(shapes, shapes, mass))
    loads = np.zeros((E, Q, F, 3))
    loads[..., 0] = dx[..., None] * values.reshape(E, Q, F)
    rhs = shapes.vector(loads).reshape(F, shapes.n)
    return np.column_stack([lu.solve(b) for b in rhs])


def interpolate(shapes, vertex_values):
    """Values (E Q, F) at the quadrature points of a mesh's vertex basis ``shapes`` of the
    vertex values (n, F)."""
    values = shapes.values(vertex_values.T)[..., 0]      # (E, Q, F)
    return values.reshape(-1, vertex_values.shape[1])


def transfer(old, new, values):
    """Quadrature values on the old mesh to the new mesh's points.

    Parameters
    ----------
    old, new : skfem.CellBasis
        P1 (vertex) bases of the old and new meshes on the same vertices, with the same
        quadrature rule; scikit-fem sorts each element's vertex indices, so an element of
        both meshes has the same quadrature points in both.
    values : ndarray, shape (E_old Q, F)
        F quantities at the old quadrature points (element-major).

    Returns
    -------
    ndarray, shape (E_new Q, F)
        Elements of both meshes: their old values; the others: :func:`recover` on the old
        mesh, then :func:`interpolate` with the new basis.
    """
    Q, F = old.dx.shape[1], values.shape[1]
    carried = interpolate(Shapes.of(new), recover(Shapes.of(old), old.dx, values))
    n = old.mesh.p.shape[1]
    key = [np.ravel_multi_index(basis.mesh.t, (n, n, n)) for basis in (old, new)]
    _, kept_old, kept_new = np.intersect1d(*key, assume_unique=True, return_indices=True)
    carried = carried.reshape(-1, Q, F)
    carried[kept_new] = values.reshape(-1, Q, F)[kept_old]
    return carried.reshape(-1, F)
