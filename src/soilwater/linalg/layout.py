"""What a Newton system tells the linear solvers: its unknowns and its solver policy.

A discretisation describes its tangents by a :class:`Layout` (the node, field, location
and residual scale of each unknown, the pressure mass matrix, the P-wave modulus) and
chooses how they are solved by a :class:`Policy`, which it passes explicitly to
:meth:`Layout.of`:

* ``iterative``: the Krylov back-end suits the discretisation, and is the default from
  :data:`soilwater.linalg.backends.KRYLOV_FROM` unknowns;
* ``single``: PARDISO factorises its tangents in single precision and refines each solve
  in double (:class:`soilwater.linalg.pardiso._Pardiso`);
* ``forcing``: the largest relative residual of an inexact-Newton Krylov solve
  (:func:`forcing`), at most :data:`FORCING_MAX` by default;
* ``smoother`` and ``strength``: the finest-level smoother and the strength-of-connection
  threshold of the Krylov back-end's AMG hierarchies.

:data:`DIRECT` is the default: a direct solver at every size, in double precision. EFG
chooses its policy from its essential conditions and stabilisation
(:func:`soilwater.efg.system.policy`), the FEM reference from its element pair
(:func:`soilwater.fem.system.policy`).

The modified Newton iteration keeps a factorisation while it contracts the residual
:data:`CONTRACTION`-fold per iteration (:func:`must_refactorise`); a single-precision
PARDISO factor is redone in double when one of its refinements does not.
"""

from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

#: A factorisation is kept while each iteration divides the residual by at least 1/this.
CONTRACTION = 0.1
#: Largest relative residual an inexact-Newton Krylov solve may stop at, unless the
#: discretisation asks for another (:attr:`Policy.forcing`; EFG does). On the FEM pairs
#: 1e-5 takes as many Newton iterations and more FGMRES iterations (``make bench``'s
#: fem-p1p1-stab step: 127 against 100 at 10^5 nodes, 137 against 108 at 3 x 10^5).
FORCING_MAX = 1e-4


def _check(owner, smoother, strength, forcing):
    """Reject an unknown ``smoother``, a ``strength`` outside [0, 1) or a ``forcing``
    outside (0, 1), the message naming ``owner``'s field."""
    if smoother not in ("gauss_seidel", "schwarz"):
        raise ValueError(f"{owner}.smoother={smoother!r}: use 'gauss_seidel' or 'schwarz'")
    if not 0.0 <= strength < 1.0:
        raise ValueError(f"{owner}.strength={strength!r}: use a threshold in [0, 1)")
    if not 0.0 < forcing < 1.0:
        raise ValueError(f"{owner}.forcing={forcing!r}: use a relative residual in (0, 1)")


@dataclass(frozen=True)
class Policy:
    """How the linear solvers treat a discretisation's tangents.

    Attributes
    ----------
    iterative : bool
        The discretisation suits the Krylov back-end (EFG with Nitsche's conditions and a
        pressure stabilisation; the inf-sup stable or stabilised FEM pairs), which
        :func:`soilwater.linalg.backends.backend` then picks by default from
        :data:`soilwater.linalg.backends.KRYLOV_FROM` unknowns. False: a direct solver at
        every size, unless ``SOILWATER_LINEAR_SOLVER`` says otherwise.
    single : bool
        PARDISO factorises the tangent in single precision and refines each solve in
        double (:data:`soilwater.linalg.backends.SINGLE`,
        :class:`soilwater.linalg.pardiso._Pardiso`): where measured to pay (``python
        docs/experiments/direct_single.py``; EFG with Nitsche's conditions and a
        stabilisation, fem-th). A penalty's tangent, whose diagonal spans 10^6, is beyond
        a single factor's refinement.
    forcing : float
        The largest relative residual of an inexact-Newton Krylov solve
        (:func:`forcing`), ``0 < forcing < 1``: :data:`FORCING_MAX` unless the
        discretisation asks for another (``python docs/experiments/krylov_newton.py``).
    smoother : str
        How the Krylov back-end's AMG V-cycles smooth their finest level:
        ``"gauss_seidel"`` (symmetric Gauss-Seidel on node blocks) or ``"schwarz"``
        (multiplicative Schwarz on overlapping aggregates,
        :class:`soilwater.linalg.krylov_schwarz.Schwarz`: dearer per sweep, it pays for MLS's
        wide stencils and for fem-th through a softening peak; ``python
        docs/experiments/krylov_smoother.py``).
    strength : float
        The strength-of-connection threshold ``theta`` of the Krylov back-end's AMG
        hierarchies, ``0 <= theta < 1``: a coupling counts (aggregates and Schwarz
        subdomains grow along it) where ``|a_ij| >= theta sqrt(|a_ii a_jj|)``. 0 (every
        coupling; pyamg's default) unless the discretisation asks for more (``python
        docs/experiments/krylov_strength.py``).

    Raises
    ------
    ValueError
        An unknown smoother, a strength outside [0, 1) or a forcing outside (0, 1).

    Examples
    --------
    >>> Policy(iterative=True, single=True).forcing == FORCING_MAX
    True
    """

    iterative: bool = False
    single: bool = False
    forcing: float = FORCING_MAX
    smoother: str = "gauss_seidel"
    strength: float = 0.0

    def __post_init__(self):
        _check("Policy", self.smoother, self.strength, self.forcing)


#: The default policy: a direct solver at every size, in double precision.
DIRECT = Policy()


@dataclass(frozen=True)
class Layout:
    """What the unknowns of a Newton system are, and how the linear solvers treat them.

    Attributes
    ----------
    groups : ndarray of int, shape (n,), or None
        The node (location) of each unknown, -1 for a rigid plate or a multiplier:
        PARDISO's node-blocked order (:func:`soilwater.linalg.backends.factorise`).
    fields : ndarray of int, shape (n,), or None
        0 and 1: displacement x and y [m]; 2: pore pressure [kPa]; -1: anything else.
    locations : ndarray, shape (n, 2), or None
        Where each unknown lives [m]: the rigid-body modes of the displacement AMG.
    scales : ndarray, shape (n,), or None
        The residual scale of each row: force or volume per unit thickness.
    mass : scipy.sparse matrix, shape (n, n), a function returning one, or None
        Pressure mass ``int N_i N_j dV`` [m2 per unit thickness] on pressure rows and
        columns, zero elsewhere; a function is called when a solver first needs it
        (:meth:`mass_matrix`). EFG gives the consistent matrix: MLS shape functions
        overlap so widely that the lumped one overstates rough pressure modes.
    modulus : float
        P-wave modulus ``K + 4G/3`` of the initial state [kPa].
    smoother, strength, iterative, single, forcing
        The discretisation's :class:`Policy` (:meth:`of`), :data:`DIRECT`'s by default.

    Raises
    ------
    ValueError
        As :class:`Policy`, naming the Layout's field.
    """

    groups: np.ndarray = None
    fields: np.ndarray = None
    locations: np.ndarray = None
    scales: np.ndarray = None
    mass: object = None
    modulus: float = 1.0
    smoother: str = DIRECT.smoother
    strength: float = DIRECT.strength
    iterative: bool = DIRECT.iterative
    single: bool = DIRECT.single
    forcing: float = DIRECT.forcing

    def __post_init__(self):
        _check("Layout", self.smoother, self.strength, self.forcing)

    @classmethod
    def of(cls, policy, **unknowns):
        """The layout of the ``unknowns`` (the other attributes) solved by ``policy``."""
        return cls(**unknowns, **asdict(policy))

    @property
    def complete(self):
        """True if the layout names enough for the Krylov back-end."""
        return all(v is not None for v in (self.fields, self.locations, self.scales,
                                           self.mass))

    def mass_matrix(self):
        """The pressure mass matrix (``mass``, built first if it is a function)."""
        return sp.csr_matrix(self.mass() if callable(self.mass) else self.mass)


def must_refactorise(lu, residual, previous):
    """True when no factorisation is kept or it contracted the residual too little."""
    return lu is None or residual > CONTRACTION * previous


def forcing(residual, previous, last, tolerance, cap=FORCING_MAX):
    """The relative residual an inexact-Newton solve stops at (Eisenstat and Walker 1996,
    choice 2 with their safeguard): ``0.9 (r_k / r_k-1)^2``, at least ``0.9 eta_k-1^2``
    when that exceeds 0.1, at most ``cap``, and no less than what takes the scaled
    residual to a tenth of the Newton ``tolerance``.

    Parameters
    ----------
    residual, previous : float
        The scaled Newton residual now and at the last iteration (``inf`` at the first).
    last : float
        The forcing of the last iteration (``cap`` at the first).
    tolerance : float
        The Newton tolerance on the scaled residual.
    cap : float
        The largest forcing (:attr:`Policy.forcing`).

    Examples
    --------
    The first solve stops at the cap; once the residual has dropped a thousandfold, at
    0.9 x (1e-3)^2:

    >>> forcing(1.0, float("inf"), FORCING_MAX, 1e-8)
    0.0001
    >>> round(forcing(1e-3, 1.0, 1e-5, 1e-10, cap=1e-5), 12)
    9e-07
    """
    eta = 0.9 * (residual / previous) ** 2 if np.isfinite(previous) else last
    if 0.9 * last**2 > 0.1:
        eta = max(eta, 0.9 * last**2)
    return float(min(max(eta, 0.1 * tolerance / residual), cap))
