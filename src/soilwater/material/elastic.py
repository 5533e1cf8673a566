"""Linear (hypo)elasticity with the Cam-clay interface, for the verification cases.

Jaumann rate of Cauchy effective stress = ``C : D`` with constant ``E`` and ``nu``;
the stress is rotated by Hughes-Winget and then ``C : dstrain`` is added, so the
update is exact for small strain and objective for large rotation.
Conventions as in :mod:`soilwater.material.camclay`.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import require
from soilwater.material.kinematics import DEVIATORIC, IDENTITY, hughes_winget
from soilwater.material.protocol import Material


@dataclass(frozen=True)
class LinearElastic(Material):
    """Isotropic linear elasticity.

    Parameters
    ----------
    E : float
        Young's modulus (stress unit of the case).
    nu : float
        Poisson ratio in (-1, 0.5).
    p0 : float
        Initial isotropic mean effective stress (compression positive; 0 by default).
    e0 : float
        Initial void ratio (1 by default); it sets the specific volume ``v = 1 + e`` of the
        state, which only the weight under gravity and a void-ratio-dependent
        permeability read.

    Examples
    --------
    >>> import numpy as np
    >>> mat = LinearElastic(E=1.0, nu=0.25)
    >>> stress, state = mat.initial_state(1)
    >>> stress, state, C = mat.update(stress, state, np.array([[1e-3, 0, 0, 0]]), np.zeros(1))
    >>> np.allclose(stress[0, 0], C[0, 0, 0] * 1e-3)
    True
    """

    E: float
    nu: float
    p0: float = 0.0
    e0: float = 1.0

    def __post_init__(self):
        require(self.E > 0, f"material.E = {self.E} must be positive (Young's modulus)")
        require(-1.0 < self.nu < 0.5,
                f"material.nu = {self.nu} must lie in (-1, 0.5): use a Poisson ratio such as 0.3")
        require(self.e0 > 0, f"material.e0 = {self.e0} must be positive (void ratio)")

    @property
    def K(self):
        """Bulk modulus."""
        return self.E / (3 * (1 - 2 * self.nu))

    @property
    def G(self):
        """Shear modulus."""
        return self.E / (2 * (1 + self.nu))

    #: A linear elastic skeleton has no yield surface (no stress-point driver paths).
    plastic = False

    def moduli(self, p=None, v=None):
        """Bulk and shear moduli ``(K, G)``, the same in every state."""
        return self.K, self.G

    @property
    def stiffness(self):
        """Elastic tangent (4, 4) from Voigt strain ``(xx, yy, zz, 2xy)`` to stress."""
        return self.K * np.outer(IDENTITY, IDENTITY) + 2 * self.G * DEVIATORIC

    def k0_nc(self):
        """K0 of one-dimensional compression, ``nu / (1 - nu)``."""
        return self.nu / (1 - self.nu)

    def admissible(self, stress, state):
        """Every stress is admissible: the state unchanged."""
        return state

    def initial_state(self, n, p=None):
        """Isotropic stress ``-p I`` and the state ``{"v"}`` (specific volume ``1 + e0``)
        for n points."""
        p = self.p0 if p is None else p
        return -np.outer(np.broadcast_to(p, (n,)), IDENTITY), {"v": np.full(n, 1 + self.e0)}

    def update(self, stress, state, dstrain, dspin):
        """Rotate, then add ``C : dstrain``; returns stress, state and the tangent."""
        dstrain = np.asarray(dstrain, dtype=float)
        new = hughes_winget(stress, dspin) + dstrain @ self.stiffness.T
        v = state["v"] * np.exp(dstrain[:, :3].sum(axis=1))
        return new, {"v": v}, np.broadcast_to(self.stiffness, (len(new), 4, 4))
