"""The clay of Gibson's reference: its compression and permeability laws.

Units and signs: kPa, m, s; unit weights [kN/m3]; permeability k [m/s]. Effective vertical
stress sigma' is **compression positive**.

Compression laws, ``sigma'(e)`` (``Clay.compression``):

- ``"camclay"``: the Cam-clay lines in oedometric form, ``Cc = lambda ln 10``,
  ``Cr = kappa ln 10``: the normal compression line ``e = e_ref - lambda ln(sigma'/
  sigma_v_ref)`` and, below the pre-consolidation stress ``sigma'_p``, the swelling line
  ``e = e_ncl(sigma'_p) + kappa ln(sigma'_p/sigma')``. ``sigma'_p`` is a state per soil
  element (``ocr`` times the initial stress; it grows as the element loads past it), so
  unloading and reloading follow the swelling line. The line has ``e -> inf`` at zero
  stress: a geostatic start needs a surcharge > 0.
- ``"constant-mv"``: ``1 + e = (1 + e_ref) exp(-mv (sigma' - sigma_v_ref))``, the
  constant volume compressibility ``mv = -de/dsigma' / (1 + e)`` [1/kPa] of Xie and Leo
  (2004).

Permeability laws ``k(e)`` (``Clay.permeability_law``), each ``k_ref`` (``permeability``)
at ``e_k`` (``permeability_e``, default ``e_ref``):

- ``"constant"``: ``k = k_ref``;
- ``"taylor"``: ``k = k_ref 10^((e - e_k)/C_k)`` (``permeability_ck`` = C_k);
- ``"kozeny-carman"``: ``k = k_ref (e^3/(1+e)) / (e_k^3/(1+e_k))``;
- ``"xie-leo"``: ``k = k_ref ((1+e)/(1+e_k))^2`` (Xie and Leo's closed-form case).

"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import require

COMPRESSION_LAWS = ("camclay", "constant-mv")
PERMEABILITY_LAWS = ("constant", "taylor", "kozeny-carman", "xie-leo")


@dataclass(frozen=True)
class Clay:
    """Compression and permeability laws of the clay (module docstring for the forms).

    Parameters
    ----------
    compression : str
        ``"camclay"`` (``lam``, ``kappa``) or ``"constant-mv"`` (``mv``).
    lam, kappa : float
        Slopes of the normal compression and swelling lines in ``e``-``ln sigma'``
        (Cc = lam ln 10, Cr = kappa ln 10), ``lam > kappa > 0``.
    mv : float
        Volume compressibility [1/kPa] of ``"constant-mv"``.
    e_ref, sigma_v_ref : float
        The compression line passes through ``e_ref`` at ``sigma_v_ref`` [kPa] (defaults:
        Table 1's lambda, kappa and e0 at p'0).
    permeability : float
        k_ref [m/s].
    permeability_law : str
        ``"constant"``, ``"taylor"``, ``"kozeny-carman"`` or ``"xie-leo"``.
    permeability_e : float or None
        Void ratio e_k at which k = k_ref (default ``e_ref``).
    permeability_ck : float or None
        Taylor's C_k (> 0), required by ``"taylor"``.
    specific_gravity : float
        Gs of the solids (> 1): ``gamma_s = Gs gamma_w``.
    gamma_w : float
        Unit weight of water [kN/m3].
    """

    compression: str = "camclay"
    lam: float = 0.11
    kappa: float = 0.04
    mv: float | None = None
    e_ref: float = 0.83
    sigma_v_ref: float = 3.0
    permeability: float = 1e-8
    permeability_law: str = "constant"
    permeability_e: float | None = None
    permeability_ck: float | None = None
    specific_gravity: float = 2.65
    gamma_w: float = 9.81

    def __post_init__(self):
        require(self.compression in COMPRESSION_LAWS,
                f"compression = {self.compression!r} is unknown: use one of "
                f"{', '.join(COMPRESSION_LAWS)}")
        if self.compression == "camclay":
            require(self.lam > self.kappa > 0,
                    f"lambda = {self.lam}, kappa = {self.kappa}: need lambda > kappa > 0")
        else:
            require(self.mv is not None and self.mv > 0,
                    f"mv = {self.mv} must be > 0 [1/kPa] with compression = 'constant-mv'")
        require(self.e_ref > 0, f"e_ref = {self.e_ref} must be > 0 (a void ratio)")
        require(self.sigma_v_ref > 0, f"sigma_v_ref = {self.sigma_v_ref} must be > 0 [kPa]")
        require(self.permeability > 0, f"permeability = {self.permeability} must be > 0 "
                "[m/s]")
        require(self.permeability_law in PERMEABILITY_LAWS,
                f"permeability_law = {self.permeability_law!r} is unknown: use one of "
                f"{', '.join(PERMEABILITY_LAWS)}")
        require(self.permeability_e is None or self.permeability_e > 0,
                f"permeability_e = {self.permeability_e} must be > 0 (a void ratio)")
        if self.permeability_law == "taylor":
            require(self.permeability_ck is not None and self.permeability_ck > 0,
                    f"permeability_ck = {self.permeability_ck} must be > 0 with "
                    "permeability_law = 'taylor'")
        require(self.specific_gravity > 1, f"specific_gravity = {self.specific_gravity} "
                "must be > 1 (solids denser than water)")
        require(self.gamma_w > 0, f"gamma_w = {self.gamma_w} must be > 0 [kN/m3]")

    def void_ratio(self, sigma, sigma_p):
        """Void ratio at effective stress ``sigma`` [kPa] with pre-consolidation
        ``sigma_p`` (ignored by ``"constant-mv"``)."""
        sigma = np.asarray(sigma, dtype=float)
        if self.compression == "constant-mv":
            return (1 + self.e_ref) * np.exp(-self.mv * (sigma - self.sigma_v_ref)) - 1
        sigma_p = np.maximum(sigma_p, sigma)
        e_p = self.e_ref - self.lam * np.log(sigma_p / self.sigma_v_ref)
        return e_p + self.kappa * np.log(sigma_p / sigma)

    def virgin_stress(self, e):
        """Effective stress [kPa] on the normal compression line (or the mv law) at e."""
        if self.compression == "constant-mv":
            return self.sigma_v_ref - np.log((1 + e) / (1 + self.e_ref)) / self.mv
        return self.sigma_v_ref * np.exp((self.e_ref - e) / self.lam)

    def effective_stress(self, e, sigma_p):
        """Effective stress sigma'(e) [kPa] and its derivative dsigma'/de (< 0)."""
        if self.compression == "constant-mv":
            return self.virgin_stress(e), -1.0 / (self.mv * (1 + e))
        e_p = self.e_ref - self.lam * np.log(sigma_p / self.sigma_v_ref)
        virgin = e <= e_p
        slope = np.where(virgin, self.lam, self.kappa)
        swelling = sigma_p * np.exp((e_p - e) / self.kappa)
        sigma = np.where(virgin, self.virgin_stress(e), swelling)
        return sigma, -sigma / slope

    def permeability_of(self, e):
        """Permeability k(e) [m/s] and dk/de."""
        e = np.asarray(e, dtype=float)
        e_k = self.e_ref if self.permeability_e is None else self.permeability_e
        law = self.permeability_law
        if law == "constant":
            k = np.full_like(e, self.permeability)
            return k, np.zeros_like(e)
        if law == "taylor":
            k = self.permeability * 10.0 ** ((e - e_k) / self.permeability_ck)
            return k, k * np.log(10.0) / self.permeability_ck
        if law == "kozeny-carman":
            k = self.permeability * (e**3 / (1 + e)) / (e_k**3 / (1 + e_k))
            return k, k * (3 / e - 1 / (1 + e))
        k = self.permeability * ((1 + e) / (1 + e_k)) ** 2
        return k, 2 * k / (1 + e)

    def conductivity(self, e):
        """``K = k / (gamma_w (1 + e))`` [m/s per kPa, per unit solid height] and dK/de."""
        k, dk = self.permeability_of(e)
        K = k / (self.gamma_w * (1 + e))
        return K, (dk - k / (1 + e)) / (self.gamma_w * (1 + e))


#: The soft clay of the large-strain column: Cc = 0.92, Cr = 0.092 (Cr/Cc =
#: 0.1), e = 2.4 at 10 kPa, Gs = 2.65, Taylor's k = 1e-9 m/s at e = 2.4 with C_k = 0.5 e
#: (Tavenas et al. 1983). Table 1's clay (lambda/(1 + e) = 0.06) cannot settle more than
#: 14 % under a tenfold load; this one settles 23 %.
SOFT_CLAY = Clay(lam=0.4, kappa=0.04, e_ref=2.4, sigma_v_ref=10.0, permeability=1e-9,
                 permeability_law="taylor", permeability_ck=1.2, specific_gravity=2.65)
