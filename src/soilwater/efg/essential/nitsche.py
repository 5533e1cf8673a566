"""Nitsche's method: essential conditions that keep the EFG matrix well scaled.

MLS shape functions do not interpolate, so EFG imposes ``u_f = u_bar_f`` on the constrained
components f of a field weakly, at the boundary Gauss points (:mod:`soilwater.efg.boundary`). The
penalty adds ``alpha int v_f gap_f`` with alpha 10^6 times the stiffness scale: its error
is of the order of 1/alpha, and the diagonal of the matrix spans 10^6, so that a Krylov
solver's small relative residual says nothing about the interior. Nitsche (1971) adds
instead, to the residual of every test function v, with ``gap = u^h - u_bar``:

* consistency, ``-int v_f (s n)_f dGamma``, with s the weak form's flux (the coefficients
  of grad v: the first Piola stress ``J sigma F^-T`` for momentum, ``-dt (k / gamma_w)
  grad p`` for continuity; :mod:`soilwater.physics.weakform`): the reaction is the flux that the
  interior equations carry to the boundary, not a penalty force;
* the adjoint term, ``+int gap_f (D grad v n)_f dGamma``, with a reference operator D
  frozen over the step (at the reference state, minus the transpose of the consistency
  term: the skew-symmetric variant);
* stabilisation, ``beta int v_f gap_f dGamma``.

All three vanish for the exact solution (zero gap, exact flux): the method is consistent
for every beta, and its error is the discretisation's. Where D is the weak form's own
operator (linear elasticity), the consistency and adjoint terms cancel in ``v K v = A(v) +
beta |v_c|^2_Gamma`` (``A(v) = int grad v : D : grad v``, c the constrained components):
coercive for every beta > 0 (Burman 2012, "A penalty-free nonsymmetric Nitsche-type
method for the weak imposition of boundary conditions", SINUM 50). The symmetric variant
(adjoint term with a minus sign) needs beta above ``lambda``, the largest eigenvalue of
``int_Gamma |(D grad v n)_c|^2 = lambda A(v)``, and only for the operator it is built
with: with the elastic D against a yielding clay, whose domain form is far softer, the
unconfined compression left its homogeneous path at 3.6 % strain and stopped at 6.4 %
(measured; skew-symmetric: homogeneous to 20 %, as the penalty). The matrices are not
symmetric anyway (VCI's test gradients, finite strain). beta keeps the scale at which the
symmetric variant is coercive, ``beta = 2 lambda`` (:data:`SAFETY`; Griebel and Schweitzer
2003, "A particle-partition of unity method part V: boundary conditions"), so that the
condition is held as tightly; lambda is estimated on the strip of nodes next to the
constrained boundary (:func:`largest_eigenvalue`).

Layout: the fields and slots of :mod:`soilwater.physics.weakform` (value, d/dx, d/dy on x_n), at the
boundary points with their line weights [m per unit thickness]; every operator and
tangent is a :class:`soilwater.physics.weakform.Coefficients`, its terms in use. The consistency
term
is the weak form's flux through the boundary, an operation on terms (:func:`_through`):
a term ``(f, 1 + k, g, t)`` of the test gradient times ``n_k`` adds to the value term
``(f, 0, g, t)``; the adjoint term is the transpose of the reference operator's flux,
``(h, 0, f, 1 + l)`` -> ``(f, 1 + l, h, 0)``; the stabilisation adds ``(f, 0, f, 0)``.
Signs: the continuity equation's operator is negative (``-dt k / gamma_w``), so its D
and beta are negative and each term keeps the sign of its field's equations.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from soilwater.efg.assembly import Pattern, elasticity_coefficients, scatter
from soilwater.material.kinematics import DEVIATORIC, IDENTITY
from soilwater.physics.weakform import Coefficients

#: beta over the eigenvalue bound lambda (the symmetric variant is coercive for any factor
#: above 1, the skew-symmetric one for any beta > 0).
SAFETY = 2.0
#: Rings of neighbouring nodes added to those whose supports reach a constrained point, on
#: which :func:`largest_eigenvalue` solves (the maximiser lives next to the boundary).
RINGS = 2
#: Boundary rows up to which the eigenvalue is found densely (Lanczos above: tens of
#: back-solves instead of one per row).
DENSE = 10
#: Relative tolerance of the Lanczos eigenvalue. It is started from a fixed generic vector
#: and converged well below the round-off a run tolerates, so beta, and the results, do
#: not depend on a random start or on where the iteration happens to stop.
EIGEN_TOLERANCE = 1e-10


@dataclass(frozen=True)
class Nitsche:
    """The Nitsche terms of one configuration at the G boundary points (F fields).

    Attributes
    ----------
    normal : ndarray, shape (G, 2)
        Unit outward normals on x_n.
    weights : ndarray, shape (G,)
        Line weights [m per unit thickness].
    mask : ndarray of bool, shape (G, F)
        The constrained components.
    operator : soilwater.physics.weakform.Coefficients
        F x F fields, the terms ``(h, 0, f, 1 + l) = w mask[h] sum_k n_k D(h, 1 + k, f, 1
        + l)`` (:func:`flux_operator`): the reference flux of component h through the
        boundary per unit test gradient ``d v_f / d x_l``, times the line weight.
    beta : ndarray, shape (F,)
        Stabilisation of each field [flux per unit of the field and per m: kPa/m for the
        displacement, m/kPa for the pore pressure, whose beta is negative].
    """

    normal: np.ndarray
    weights: np.ndarray
    mask: np.ndarray
    operator: Coefficients
    beta: np.ndarray

    @classmethod
    def build(cls, bpoints, mask, D, beta):
        """Terms on :class:`soilwater.efg.boundary.BoundaryPoints` ``bpoints`` with the constrained
        components ``mask`` (G, F), the reference operator D at the points (F x F fields,
        :func:`flux_operator`) and the stabilisation ``beta`` (F,)."""
        return cls(bpoints.normal, bpoints.weights, np.asarray(mask, bool),
                   flux_operator(bpoints, mask, D), np.asarray(beta, float))

    def reaction(self, flux, gap):
        """The force the support exerts on the body at each point, (G, F): ``w (s n -
        beta gap)`` on constrained components (s n the weak form's flux through the
        boundary; for the displacement a force per unit thickness, y up positive).

        Parameters
        ----------
        flux : ndarray, shape (G, F, 3)
            The weak form's residual coefficients at the boundary points, line weights
            included (:func:`soilwater.physics.weakform.residual`; the gradient slots are read).
        gap : ndarray, shape (G, F)
            ``u^h - u_bar`` per component (read where constrained).
        """
        through = np.einsum("gk,gfk->gf", self.normal, flux[:, :self.beta.size, 1:])
        return self.mask * (through - self.beta * self.weights[:, None] * gap)

    def residual(self, flux, gap):
        """Residual coefficients (G, F, 3) of the three terms (arguments as
        :meth:`reaction`); the adjoint term reads :attr:`operator` transposed,
        ``r[:, f, 1 + l] += gap_h T(h, 0, f, 1 + l)``."""
        r = np.zeros(gap.shape + (3,))
        r[:, :, 0] = -self.reaction(flux, gap)
        for (h, _, f, t), value in self.operator.columns().items():
            r[:, f, t] += gap[:, h] * value
        return r

    def tangent(self, c):
        """Tangent coefficients of the three terms, from the weak form's tangent ``c``
        (:class:`soilwater.physics.weakform.Coefficients` of F x F fields) at the boundary points.

        Consistency: the terms of c's test gradient, through the boundary
        (:func:`_through`) on the constrained components, with a minus sign; adjoint: the
        terms ``(f, 1 + l, h, 0)`` of :attr:`operator` transposed; stabilisation: ``(f,
        0, f, 0) += beta_f w mask[f]``. Returns Coefficients of c's fields.
        """
        consistency = _through(c, self.normal, np.where(self.mask, -1.0, 0.0))
        adjoint = {(f, t, h, 0): value
                   for (h, _, f, t), value in self.operator.columns().items()}
        stabilisation = {(f, 0, f, 0): self.beta[f] * self.weights * self.mask[:, f]
                         for f in range(self.beta.size)}
        return _summed((consistency, adjoint, stabilisation), c.fields)


def flux_operator(bpoints, mask, D):
    """The reference flux through the boundary, ``T(h, 0, f, 1 + l) = w_g mask[g, h]
    sum_k n_k D(h, 1 + k, f, 1 + l)``, of D's fields.

    ``D(h, 1 + k, f, 1 + l) = d s_hk / d(d v_f / d x_l)`` is the reference operator at the
    boundary points ``bpoints`` (:class:`soilwater.efg.boundary.BoundaryPoints`), as
    :class:`soilwater.physics.weakform.Coefficients` of its gradient terms without weight; ``mask``
    (G, F) the constrained components.

    Examples
    --------
    One field at one point with normal (0.6, 0.8) and line weight 2: the terms ``(0, 1,
    0, 1)`` and ``(0, 2, 0, 1)`` of D pass through the boundary into ``(0, 0, 0, 1)``.

    >>> from types import SimpleNamespace
    >>> D = Coefficients.of({(0, 1, 0, 1): np.array([5.0]),
    ...                      (0, 2, 0, 1): np.array([10.0])}, (1, 1))
    >>> bp = SimpleNamespace(normal=np.array([[0.6, 0.8]]), weights=np.array([2.0]))
    >>> T = flux_operator(bp, np.array([[True]]), D)
    >>> T.terms, T.values.tolist()
    (((0, 0, 0, 1),), [[22.0]])
    """
    factor = bpoints.weights[:, None] * np.asarray(mask)
    return Coefficients.of(_through(D, bpoints.normal, factor), D.fields)


def _through(c, normal, factor):
    """The flux of coefficients ``c`` through the boundary, ``{(f, 0, g, t): (G,)}``: each
    term ``(f, 1 + k, g, t)`` of the test gradient times ``n_k`` adds to the value term
    ``(f, 0, g, t)``, the sum then times ``factor[:, f]`` (G, F); terms of the test value
    slot carry no flux and are left out."""
    terms = {}
    for (f, s, g, t), value in c.columns().items():
        if s:
            flux = normal[:, s - 1] * value
            terms[f, 0, g, t] = terms[f, 0, g, t] + flux if (f, 0, g, t) in terms else flux
    return {term: factor[:, term[0]] * value for term, value in terms.items()}


def _summed(parts, fields):
    """:class:`soilwater.physics.weakform.Coefficients` of the sum of term dicts ``{(f, s, g, t):
    (G,)}`` (a term in several parts is added)."""
    total = {}
    for part in parts:
        for term, value in part.items():
            total[term] = total[term] + value if term in total else value
    return Coefficients.of(total, fields)


def gradient_operator(C):
    """The operator ``D(f, 1 + k, g, 1 + l) = d sigma_fk / d(d u_g / d x_l)`` of Voigt
    tangents C (P, 4, 4) [kPa] (strain ``(xx, yy, zz, 2xy)`` to stress ``(xx, yy, zz,
    xy)``), made symmetric (``(C + C^T) / 2``): :class:`soilwater.physics.weakform.Coefficients` of
    2 x
    2 fields, its gradient terms without weight
    (:func:`soilwater.efg.assembly.elasticity_coefficients` of unit weights)."""
    C = np.asarray(C, float)
    return elasticity_coefficients(np.ones(len(C)), (C + np.swapaxes(C, 1, 2)) / 2)


def isotropic(K, G):
    """Voigt tangents (P, 4, 4) of isotropic elasticity with bulk and shear moduli K, G
    (P,) [kPa]."""
    return (np.asarray(K)[:, None, None] * np.outer(IDENTITY, IDENTITY)
            + 2 * np.asarray(G)[:, None, None] * DEVIATORIC)


def largest_eigenvalue(domain, boundary, rings=RINGS):
    """Estimate of the largest lambda of ``sum_g w_g |(D grad v n)_c|^2 = lambda int grad v
    : D : grad v dOmega`` [the operator's unit per m], the bound that fixes beta.

    Solved as the largest eigenvalue of ``Q A^-1 Q^T`` (Lanczos; dense when small), Q the
    boundary rows ``T grad v / sqrt(w)``, A the domain form, over the functions of the
    nodes that reach a constrained point and ``rings`` rings of their neighbours (zero
    elsewhere): a lower bound that grows to the exact lambda with the rings (the maximiser
    decays away from the boundary; measured in :mod:`soilwater.studies.essential.study`), which the
    factor :data:`SAFETY` covers. A's null space (rigid motions, constants) carries no
    boundary flux; a shift of 1e-10 of A's largest diagonal makes A regular there.

    Parameters
    ----------
    domain : tuple
        ``(shape, weights, D)``: trial functions at the domain integration points (plain
        MLS gradients), their weights (M,) [m2 per unit thickness] and the positive
        semi-definite operator D there (:class:`soilwater.physics.weakform.Coefficients` of F x F
        fields, gradient terms without weight; that of the boundary terms, its sign made
        positive).
    boundary : tuple
        ``(shape_b, weights_b, T)``: functions at the boundary points, their line weights
        (G,) [m] and :attr:`Nitsche.operator` (its sign does not matter).
    rings : int or None
        Neighbour rings of the strip; None: every node (the exact lambda).

    Returns
    -------
    float
        0 when no boundary row carries a flux.
    """
    shape, weights, D = domain
    Q = _boundary_rows(*boundary)
    if Q.shape[0] == 0:
        return 0.0
    n, F = shape.phi.shape[1], D.fields[0]
    nodes = _strip(shape, Q, rings)
    dofs = (np.arange(F)[:, None] * n + nodes).ravel()
    A = _domain_form(shape, weights, D, nodes)[dofs][:, dofs]
    shift = 1e-10 * A.diagonal().max()
    lu = spla.splu(sp.csc_matrix(A + shift * sp.identity(len(dofs))))
    Q = Q[:, dofs].tocsr()
    if Q.shape[0] <= DENSE:
        S = Q @ lu.solve(Q.T.toarray())
        return float(np.linalg.eigvalsh(0.5 * (S + S.T))[-1])
    op = spla.LinearOperator((Q.shape[0],) * 2, dtype=float,
                             matvec=lambda x: Q @ lu.solve(Q.T @ np.ravel(x)))
    start = np.random.default_rng(0).standard_normal(Q.shape[0])    # generic, repeatable
    return float(spla.eigsh(op, k=1, which="LA", v0=start, tol=EIGEN_TOLERANCE,
                            return_eigenvectors=False)[0])


def _boundary_rows(shape_b, weights_b, T):
    """Q (R, F n): per constrained component h at a point g, the row ``sum_l T(h, 0, f, 1
    + l) dphi_l(x_g) / sqrt(w_g)`` in the columns ``(f, node)``, one term of T at a time;
    rows without flux dropped."""
    G, F, n = len(weights_b), T.fields[0], shape_b.phi.shape[1]
    point = np.repeat(np.arange(G), np.diff(shape_b.indptr))              # of each entry
    slots = (shape_b.phi.data, shape_b.dphi_dx.data, shape_b.dphi_dy.data)
    rows, cols, values = [], [], []
    for (h, _, f, t), value in T.columns().items():
        rows.append(h * G + point)
        cols.append(f * n + shape_b.indices)
        values.append((value / np.sqrt(weights_b))[point] * slots[t])
    Q = sp.csr_matrix((np.concatenate(values),
                       (np.concatenate(rows), np.concatenate(cols))), shape=(F * G, F * n))
    Q.eliminate_zeros()
    return Q[np.flatnonzero(np.diff(Q.indptr))]


def _strip(shape, Q, rings):
    """Nodes (sorted) whose functions enter Q, grown by ``rings`` rings of neighbours
    (nodes that share an integration point); every node when ``rings`` is None."""
    n = shape.phi.shape[1]
    if rings is None:
        return np.arange(n)
    reached = np.zeros(n)
    reached[np.unique(Q.indices % n)] = 1.0
    incidence = _incidence(shape)
    for _ in range(rings):
        reached = incidence.T @ (incidence @ reached)
    return np.flatnonzero(reached)


def _domain_form(shape, weights, D, nodes):
    """``int grad v : D : grad u dOmega`` (F n, F n), fields blocked, from the integration
    points that see one of ``nodes`` (exact on their rows and columns); D's terms times
    the weights at those points."""
    seen = np.zeros(shape.phi.shape[1])
    seen[nodes] = 1.0
    rows = np.flatnonzero(_incidence(shape) @ seen)
    part = shape.subset(rows)
    coeff = Coefficients(D.terms, weights[rows, None] * D.values[rows], D.fields)
    pattern = Pattern.build((part, part))
    return pattern.matrix(scatter(pattern, part, part, coeff), *D.fields).tocsr()


def _incidence(shape):
    """Point-node incidence (P, N) of the shape functions' pattern, ones."""
    phi = shape.phi
    return sp.csr_matrix((np.ones(phi.nnz), phi.indices, phi.indptr), shape=phi.shape)
