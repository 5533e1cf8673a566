"""The pore fluid and the coupling: permeability and its laws k(e), unit weight, Biot.

:class:`Fluid` holds the ``[material]`` keys of :data:`soilwater.material.presets.FLUID_KEYS`;
the soil skeleton is the rest of that table (:mod:`soilwater.material.presets`). Units are
those of the case (kPa, m, s in the built-in cases).
"""

from dataclasses import dataclass

import numpy as np

#: The laws k(e) of ``material.permeability_law`` (:meth:`Fluid.mobility_at`).
PERMEABILITY_LAWS = ("constant", "taylor", "kozeny-carman", "xie-leo")


@dataclass(frozen=True)
class Fluid:
    """Pore fluid and coupling: permeability k [m/s] and its law, gamma_w [kN/m3], Biot
    alpha, S [1/kPa], and the specific gravity Gs of the solids (their weight under
    gravity).

    The Darcy mobility entering the continuity equation is ``k / gamma_w``. With
    ``permeability_law = "constant"`` k is ``permeability``; otherwise it falls with the
    void ratio e (:meth:`mobility_at`): Taylor's ``k = k_ref 10^((e - e_k) / C_k)``,
    Kozeny-Carman's ``k = k_ref (e^3 / (1 + e)) / (e_k^3 / (1 + e_k))`` or Xie and Leo's
    ``k = k_ref ((1 + e) / (1 + e_k))^2`` (with a constant-m_v skeleton, the law of their
    closed form), with ``k_ref = permeability``, ``e_k = permeability_e`` and ``C_k =
    permeability_ck``.
    """

    permeability: float = 0.0
    gamma_w: float = 9.81
    biot_alpha: float = 1.0
    storage: float = 0.0
    permeability_law: str = "constant"
    permeability_e: float | None = None
    permeability_ck: float | None = None
    specific_gravity: float = 2.65

    @property
    def mobility(self):
        """``k / gamma_w`` [m2/(kPa s)] at the reference void ratio (``k_ref``)."""
        return self.permeability / self.gamma_w

    def mobility_at(self, v):
        """``k(e) / gamma_w`` [m2/(kPa s)] and its derivative with respect to the specific
        volume ``v = 1 + e``, at each point.

        Parameters
        ----------
        v : array_like
            Specific volume ``1 + e`` [-] at each point.

        Returns
        -------
        k : ndarray
            Mobility ``k(e) / gamma_w`` [m2/(kPa s)], shaped as ``v``.
        dk : ndarray
            Its derivative ``d(k / gamma_w) / dv`` [m2/(kPa s)]; zero for a constant k.

        Examples
        --------
        Taylor's law falls tenfold per ``C_k`` of void ratio:

        >>> fluid = Fluid(permeability=1e-8, permeability_law="taylor",
        ...               permeability_e=1.0, permeability_ck=0.5)
        >>> k, dk = fluid.mobility_at(np.array([2.0, 1.5]))
        >>> [round(float(x), 6) for x in k * fluid.gamma_w / 1e-8]
        [1.0, 0.1]
        """
        v = np.asarray(v, dtype=float)
        if self.permeability_law == "constant":
            return np.full_like(v, self.mobility), np.zeros_like(v)
        e, e_k = v - 1.0, self.permeability_e
        if self.permeability_law == "taylor":
            k = self.mobility * 10.0 ** ((e - e_k) / self.permeability_ck)
            return k, k * np.log(10.0) / self.permeability_ck
        if self.permeability_law == "xie-leo":
            k = self.mobility * (v / (1.0 + e_k)) ** 2
            return k, 2.0 * k / v
        k = self.mobility * (e**3 / v) / (e_k**3 / (1.0 + e_k))
        return k, k * (3.0 / e - 1.0 / v)
