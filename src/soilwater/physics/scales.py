"""The residual scales of a coupled run, from the case's initial state (:class:`Scales`).

Both coupled solvers converge a step against them
(:data:`soilwater.nonlinear.newton.TOLERANCE`), take their penalty factors and stabilisation
coefficients from them, and pin the mean pore pressure of a confined undrained body by their
rule (:attr:`Scales.pin_pressure`).
"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import require
from soilwater.material.kinematics import invariants
from soilwater.physics.geostatic import buoyant_weight, initial_state


#: How far apart (a factor) moduli, loads and the fluid storage may lie (:meth:`Scales.
#: require_in_range`).
RANGE = 1e12


@dataclass(frozen=True)
class Scales:
    """Constants of a coupled run, from the case's initial state.

    Attributes
    ----------
    stress : float
        Stress scale: the largest initial effective stress, edge traction, footing stress
        (:func:`_footing_stresses`) or buoyant weight of the height [kPa].
    modulus : float
        P-wave modulus ``K + 4G/3`` of the initial state, the median over the nodes [kPa].
    h : float
        Smallest nodal spacing [m].
    pin_pressure : bool
        True for a confined body (no free or rigid component, no drained edge) with
        incompressible constituents: its pore pressure is defined up to a constant, and
        the solvers pin the mean change to zero.
    shear : float
        Shear modulus G of the initial state, the median over the nodes [kPa].

    Notes
    -----
    A step has converged when the displacement residual is below ``TOLERANCE x stress x
    h`` (force per unit thickness) and the continuity residual below ``TOLERANCE x
    stress x h^2 / modulus`` (volume per unit thickness).
    """

    stress: float
    modulus: float
    h: float
    pin_pressure: bool
    shear: float

    @classmethod
    def of(cls, case, material):
        effective, state = initial_state(case, material, case.nodes())
        edges = [edge for _, edge in case.boundary.items()]
        tractions = [e.largest_traction for e in edges]
        p, _ = invariants(effective)
        modulus = float(np.median(material.constrained_modulus(p, state["v"])))
        free = any({"free", "rigid"} & (kx | ky) for kx, ky in
                   (edge.kinds(case.edge_length(side)) for side, edge in case.boundary.items()))
        pin = case.fluid.storage == 0 and not free and not case.boundary.drained
        weight = buoyant_weight(case, state["v"]).max() * case.geometry.height
        scales = cls(max([abs(effective).max(), *tractions, weight,
                          *_footing_stresses(case, modulus), 1e-12]),
                     modulus, float(min(case.spacing)), pin,
                     float(np.median(material.moduli(p, state["v"])[1])))
        scales.require_in_range(case.fluid.storage)
        return scales

    def require_in_range(self, storage):
        """Refuse moduli, loads and a fluid storage so far apart that a step's
        displacements or pressures fall below round-off: the P-wave modulus within
        :data:`RANGE` times the largest load or stress either way (when anything loads the
        soil), and ``storage x modulus`` (how much more compressible the water is than the
        skeleton) at most :data:`RANGE`.

        Raises
        ------
        InputError
            Naming the two values and that their size or units are the likely cause.
        """
        loaded = self.stress > 1e-12
        require(not loaded or 1 / RANGE <= self.modulus / self.stress <= RANGE,
                f"the soil's initial P-wave modulus ({self.modulus:.3g}) and the largest load "
                f"or stress ({self.stress:.3g}) are more than {RANGE:.0e} times apart, which "
                "puts the displacements or the strains out of double precision: check the "
                "moduli's and loads' size and units")
        require(storage * self.modulus <= RANGE,
                f"material.storage = {storage:.3g} makes the water {storage * self.modulus:.3g} "
                "times more compressible than the skeleton (P-wave modulus "
                f"{self.modulus:.3g}): the pore pressure falls below round-off; check its size "
                "and units (1/kPa in the built-in cases)")

    @property
    def perturbation(self):
        """``h^2 / (4 M)`` [m2/kPa]: the coefficient of the flow-equation perturbation
        ``-beta int grad(p - p_n) . grad(q)`` of Aguilar, Gaspar, Lisbona and Rodrigo
        (2008), with the initial P-wave modulus M and the smallest nodal spacing h."""
        return self.h**2 / (4 * self.modulus)

    @property
    def projection(self):
        """``1 / G`` [1/kPa]: the coefficient of the polynomial pressure projection ``-tau
        int (dp - Pi dp)(q - Pi q)`` (:func:`soilwater.physics.weakform.fluctuation`), the
        inverse viscosity of Dohrmann and Bochev (2004) read as the initial shear modulus of
        the skeleton."""
        return 1.0 / self.shear

    @property
    def force(self):
        """Residual scale of equilibrium [force per unit thickness]."""
        return self.stress * self.h

    @property
    def volume(self):
        """Residual scale of continuity [volume per unit thickness]."""
        return self.stress * self.h**2 / self.modulus


def _footing_stresses(case, modulus):
    """Stress scales of the footings [kPa]: ``force / width`` under load control (``to -
    from``, or a mesh group's length), ``modulus x rate x time.end / height`` (the
    oedometric stress of the final settlement over the depth) under velocity control."""
    for side, seg in case.boundary.segments():
        if seg.load_controlled:
            yield abs(seg.force) / (case.edge_length(side) if seg.whole
                                    else seg.end - seg.start)
        elif seg.footing:
            yield modulus * abs(seg.settlement_rate) * case.time.end / case.geometry.height
