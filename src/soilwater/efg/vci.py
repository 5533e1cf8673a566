"""Variationally consistent integration: test-function gradients that pass the patch test.

With background-cell quadrature, MLS gradients do not satisfy the discrete divergence
theorem ``sum_q w_q grad(phi_I)(x_q) = sum_g w_g phi_I(x_g) n_g`` (domain points q,
boundary points g), so EFG fails the linear patch test by an integration error (Dolbow
and Belytschko 1999). Chen, Hillman and Rueter (2013, "An arbitrary order variationally
consistent integration for Galerkin meshfree methods", IJNME 95) restore it by adding to
the gradient of each TEST function a constant over its support,

    xi_I = (sum_g w_g phi_I(x_g) n_g - sum_q w_q grad(phi_I)(x_q)) / sum_{q in supp I} w_q,

while the trial functions keep their MLS gradients (a Petrov-Galerkin scheme). A linear
field is then reproduced exactly by the discrete equations with any quadrature.
"""

import dataclasses

import numpy as np
from scipy.sparse import csr_array


def corrected(shape, weights, shape_boundary, boundary_weights, normals):
    """Test shape functions with consistent gradients (same pattern, same values).

    Parameters
    ----------
    shape : ShapeFunctions
        At the domain integration points.
    weights : ndarray, shape (M,)
        Domain integration weights [m2 per unit thickness].
    shape_boundary : ShapeFunctions
        At the boundary integration points.
    boundary_weights : ndarray, shape (G,)
        Line weights [m per unit thickness].
    normals : ndarray, shape (G, 2)
        Unit outward normals.

    Returns
    -------
    ShapeFunctions
        ``dphi_dx`` and ``dphi_dy`` shifted by ``xi_I`` on every stored entry of node I.
    """
    measure = csr_array((np.ones_like(shape.phi.data), shape.indices, shape.indptr),
                        shape=shape.phi.shape).T @ weights
    columns = shape.indices
    grads = []
    for derivative, n in ((shape.dphi_dx, normals[:, 0]), (shape.dphi_dy, normals[:, 1])):
        mismatch = shape_boundary.phi.T @ (boundary_weights * n) - derivative.T @ weights
        xi = mismatch / np.where(measure > 0, measure, 1.0)
        grads.append(csr_array((derivative.data + xi[columns], columns, shape.indptr),
                               shape=shape.phi.shape))
    return dataclasses.replace(shape, dphi_dx=grads[0], dphi_dy=grads[1])
