"""Vectorised FEM assembly from scikit-fem basis arrays (no loops over elements).

A field's shape data are stacked as ``S[a, s, e, q]``: local basis function a, slot s
(0: value, 1: d/dx, 2: d/dy on the basis' mesh), element e, quadrature point q. Block
coefficients are :class:`soilwater.physics.weakform.Coefficients` at the ``E Q`` quadrature points
(element-major), pairing test field f, slot s with trial field g, slot t, quadrature
weights included.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Shapes:
    """Shape data of a scalar basis: ``S`` (nb, 3, E, Q), ``dofs`` (nb, E), ``n`` DOFs."""

    S: np.ndarray
    dofs: np.ndarray
    n: int

    @classmethod
    def of(cls, basis):
        S = np.stack([np.concatenate([np.asarray(b[0])[None], b[0].grad]) for b in basis.basis])
        return cls(S, basis.element_dofs, basis.N)

    def values(self, x):
        """Value and gradient of fields at the points: ``(E, Q, 3)`` or ``(E, Q, F, 3)``.

        ``x`` is (n,) for one field or (F, n) for F fields sharing the basis.
        """
        local = np.asarray(x)[..., self.dofs]                       # (..., nb, E)
        return np.einsum("...ae,aseq->eq...s", local, self.S)

    def vector(self, coeff):
        """``sum_q S[a, s] coeff[e, q, f, s]`` scattered to (F n,), fields blocked."""
        local = np.einsum("aseq,eqfs->fae", self.S, coeff)
        rows = (np.arange(local.shape[0])[:, None, None] * self.n + self.dofs[None])
        return np.bincount(rows.ravel(), local.ravel(), minlength=local.shape[0] * self.n)


def block(test, trial, coeff):
    """The sparse block ``sum_q test.S[a, s] c[e q, f, s, g, t] trial.S[b, t]``.

    Rows ``f test.n + test.dofs[a]``, columns ``g trial.n + trial.dofs[b]``; batched
    matrix products over (element, point), one field pair ``(f, g)`` of ``coeff``
    (:class:`soilwater.physics.weakform.Coefficients`) at a time. Besides the element matrices (E,
    F,
    G, a, b) it allocates, per pair, its slot matrices (E Q, 3, 3) and the products (E, Q,
    a, b): never all field pairs' coefficients at once.
    """
    E, Q = test.S.shape[2:]
    Sa = test.S.transpose(2, 3, 0, 1)                                # (E, Q, a, s)
    Sb = trial.S.transpose(2, 3, 1, 0)                               # (E, Q, t, b)
    F, G = coeff.fields
    nb_a, nb_b = len(test.S), len(trial.S)
    local = np.zeros((E, F, G, nb_a, nb_b))
    for f, g in coeff.pairs:
        local[:, f, g] = (Sa @ coeff.slots(f, g).reshape(E, Q, 3, 3) @ Sb).sum(axis=1)
    rows = np.arange(F)[:, None, None, None] * test.n + test.dofs.T[:, None, None, :, None]
    cols = np.arange(G)[:, None, None] * trial.n + trial.dofs.T[:, None, None, None, :]
    rows, cols = np.broadcast_arrays(rows, cols)
    return sp.csr_matrix((local.ravel(), (rows.ravel(), cols.ravel())),
                         shape=(F * test.n, G * trial.n))
