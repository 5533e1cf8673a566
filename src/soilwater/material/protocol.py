"""The material protocol: what every constitutive model of the skeleton provides.

A model subclasses :class:`Material` and implements its abstract methods; the solvers,
the stress-point driver and the verification call nothing else. Stresses are Cauchy
effective stresses, tension positive, stored ``(xx, yy, zz, xy)``; strain increments are
Voigt ``(xx, yy, zz, 2xy)``; p' is compression positive. :func:`soilwater.material.presets.
material_from_spec` builds a model from a case's ``[material]`` table.
"""

from abc import ABC, abstractmethod


class Material(ABC):
    """A constitutive model of the soil skeleton, on arrays of points.

    Attributes
    ----------
    plastic : bool
        True when the model yields (the stress-point driver then has paths for it).
    """

    plastic = False

    @abstractmethod
    def initial_state(self, n, p=None):
        """Stress (n, 4) and state (dict of (n,) arrays) of n points at the initial
        isotropic mean effective stress p' (default: the model's)."""

    @abstractmethod
    def update(self, stress, state, dstrain, dspin):
        """One step on every point: returns the stress, the state and the consistent
        tangent (n, 4, 4) from a Voigt strain increment to a stress increment.

        ``dstrain`` is the stretching increment ``D dt`` (n, 4) and ``dspin`` the spin
        increment ``W_xy dt`` (n,); the stress is rotated objectively by the spin.
        """

    @abstractmethod
    def admissible(self, stress, state):
        """The state made admissible for the stress: a stress carried to new points (the
        FEM reference's re-meshing, :mod:`soilwater.fem.transfer`) may lie outside the
        yield surface of its carried state, which the return mapping does not allow as
        a start. Returns the state (dict of (n,) arrays) with the stress (n, 4) on or
        inside the yield surface."""

    @abstractmethod
    def k0_nc(self):
        """The ratio ``sigma'_h / sigma'_v`` of normally consolidated one-dimensional
        compression (``initial.k0 = "nc"`` of a geostatic start,
        :mod:`soilwater.physics.geostatic`)."""

    @abstractmethod
    def moduli(self, p=None, v=None):
        """Bulk and shear moduli ``(K, G)`` at mean effective stress p' and specific
        volume v (default: the initial state), in the case's stress unit."""

    def constrained_modulus(self, p=None, v=None):
        """P-wave (oedometric) modulus ``K + 4G/3`` at p' and v (default: initial)."""
        K, G = self.moduli(p, v)
        return K + 4 * G / 3
