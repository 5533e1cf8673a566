"""The finite-volume system of Gibson's equation on a column, and its time levels.

Coordinates
-----------
``z`` is the reduced (solid-volume) coordinate of Gibson, England and Hussey (1967):
``dz = dxi / (1 + e)``, from 0 at the base to ``Z`` at the top, ``Z`` the layer's volume
of solids per unit area (constant in time). A solid particle keeps its z; its height is
``xi(z, t) = int_0^z (1 + e) dz``.

Equations
---------
Equilibrium of the mixture with the pore water pressure split into hydrostatic and excess
``u_e`` (the water table fixed, at the initial top) gives, per unit solid volume,
``d(sigma' + u_e)/dz = -gamma'``, ``gamma' = (Gs - 1) gamma_w`` (zero for a weightless
layer), so

    sigma'(z, t) + u_e(z, t) = sigma'_top(t) + gamma' (Z - z),

with ``sigma'_top(t) = sigma'_0 + q(t)`` the effective stress at the drained top under
the surcharge ``q`` (``sigma'_0`` is 0 for a geostatic start and the deposit's stress for
a freshly deposited layer: the starts of :class:`soilwater.references.gibson.Column`).
Continuity of water and solids with Darcy's law for the discharge relative to the
solids, ``F = -(k/gamma_w) du_e/dxi`` (upward positive), is

    de/dt = -dF/dz,   F = K(e) (gamma' + dsigma'/dz),   K = k(e) / (gamma_w (1 + e)),

which with ``sigma' = sigma'(e)`` is Gibson's equation for the void ratio (z upward):

    de/dt + (Gs - 1) d/de[k/(1+e)] de/dz + d/dz[k/(gamma_w (1+e)) dsigma'/de de/dz] = 0.

Boundary conditions: the top is drained, ``u_e = 0`` so ``sigma' = sigma'_top(t)``; the
base is impermeable (``F = 0``) or drained (``sigma' = sigma'_top + gamma' Z``). The
total pore pressure is ``p_w = u_e + gamma_w (H0 - xi)`` (zero hydrostatic part for a
weightless layer).

Numerics
--------
Cell-centred finite volumes in z (``cells`` equal cells of solid height ``Z/cells``; the
void ratio per cell is the unknown, so the volume of water is conserved to round-off);
face conductivity at the mean void ratio of the two cells; the drained faces take the
boundary stress half a cell away. ``Z`` is chosen so that the discrete initial height is
exactly ``H0``. The geostatic discrete state is an exact equilibrium (sigma' linear in
z), so a run without load change stays put to round-off.
"""

import numpy as np
from scipy.optimize import brentq


class Discrete:
    """The finite-volume system of a column on ``cells`` cells: rates and Jacobian.

    Parameters
    ----------
    column : soilwater.references.gibson.Column
    cells : int
        Equal cells of solid height ``Z / cells``.
    """

    def __init__(self, column, cells):
        self.column, self.clay, self.n = column, column.clay, cells
        self.gamma = column.buoyant_weight
        if column.start == "deposited":
            e0 = column.e_deposited
            self.base_stress = float(self.clay.virgin_stress(e0))
            self.Z = column.height / (1 + e0)
            self._grid()
            self.e0 = np.full(cells, float(e0))
            self.sigma_p = np.full(cells, self.base_stress)
        else:
            self.base_stress = 0.0
            q0 = column.surcharge

            def excess_height(Z):
                self.Z = Z
                self._grid()
                return np.sum(1 + self._geostatic(q0)[0]) * self.dz - column.height

            self.Z = brentq(excess_height, 1e-9 * column.height, column.height,
                            xtol=1e-15 * column.height, rtol=8.9e-16)
            self._grid()
            self.e0, self.sigma_p = self._geostatic(q0)

    def _grid(self):
        self.dz = self.Z / self.n
        self.zc = (np.arange(self.n) + 0.5) * self.dz

    def _geostatic(self, q0):
        """Void ratio and pre-consolidation stress of the cells in equilibrium under q0."""
        sigma = q0 + self.gamma * (self.Z - self.zc)
        sigma_p = self.column.ocr * sigma
        return self.clay.void_ratio(sigma, sigma_p), sigma_p

    def top_stress(self, t):
        return self.base_stress + self.column.surcharge_at(t)

    def rates(self, e, t, sigma_p):
        """de/dt per cell and the Jacobian's diagonals (lower, main, upper)."""
        clay, dz, g = self.clay, self.dz, self.gamma
        s, ds = clay.effective_stress(e, sigma_p)
        n = self.n
        F = np.zeros(n + 1)             # upward discharge through faces 0 (base) .. n (top)
        below = np.zeros(n + 1)         # dF_face / de of the cell below it
        above = np.zeros(n + 1)         # ... and of the cell above it
        ef = 0.5 * (e[:-1] + e[1:])
        K, dK = clay.conductivity(ef)
        grad = g + (s[1:] - s[:-1]) / dz
        F[1:-1] = K * grad
        below[1:-1] = 0.5 * dK * grad - K * ds[:-1] / dz
        above[1:-1] = 0.5 * dK * grad + K * ds[1:] / dz
        top = self.top_stress(t)
        Kt = clay.conductivity(clay.void_ratio(top, sigma_p[-1]))[0]
        F[-1] = Kt * (g + (top - s[-1]) * 2 / dz)
        below[-1] = -Kt * 2 * ds[-1] / dz
        if self.column.drained_bottom:
            bottom = top + g * self.Z
            Kb = clay.conductivity(clay.void_ratio(bottom, sigma_p[0]))[0]
            F[0] = Kb * (g + (s[0] - bottom) * 2 / dz)
            above[0] = Kb * 2 * ds[0] / dz
        rate = -(F[1:] - F[:-1]) / dz
        jac = (below[1:-1] / dz, -(below[1:] - above[:-1]) / dz, -above[1:-1] / dz)
        return rate, jac

    def profiles(self, e, t, sigma_p):
        """Height of the cell centres, sigma', u_e, p_w and k of a state."""
        clay, col = self.clay, self.column
        faces = np.concatenate([[0.0], np.cumsum((1 + e) * self.dz)])
        xi = faces[:-1] + 0.5 * (1 + e) * self.dz
        s = clay.effective_stress(e, sigma_p)[0]
        u = self.top_stress(t) + self.gamma * (self.Z - self.zc) - s
        hydro = clay.gamma_w * (col.height - xi) if col.self_weight else np.zeros_like(xi)
        return faces[-1], xi, s, u, u + hydro, clay.permeability_of(e)[0]


def time_levels(times, load_times, t_first, steps_per_decade):
    """Time levels: 0, geometric from ``t_first`` to the last output time, and every output
    and load time (sorted, unique)."""
    t_end = max(times)
    count = max(1, int(np.ceil(np.log10(t_end / t_first) * steps_per_decade)))
    geometric = np.geomspace(t_first, t_end, count + 1) if t_end > t_first else []
    extra = [t for t in load_times if t < t_end]
    return np.unique(np.concatenate([[0.0], geometric, times, extra]))
