"""Several soils in one body: the material regions of a mesh (its physical surfaces).

:class:`Regions` is a :class:`~soilwater.material.protocol.Material` whose every point
belongs to one region, each with its own skeleton (any model) and permeability. The
region travels with the point as part of its state, ``state["region"]`` (the index into
:attr:`Regions.names`, stored as a float so that every transfer of state carries it like
the others, and rounded where read: a point that a transfer puts between two regions
takes the nearer one). A point's update is its region's model's; a state key that one
region's model has and another's lacks (``pc`` of Cam-clay beside an elastic fill) is 0
at the other's points.

Per point and region as well: the pore fluid's permeability (:func:`fluid_at`). The
water (``gamma_w``, Biot alpha, storage, the permeability law and its e_k, C_k) and the
solids' specific gravity are the case's, common to all regions.
"""

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from soilwater.material.protocol import Material


@dataclass(frozen=True)
class Regions(Material):
    """The skeletons of named regions and their permeabilities.

    Parameters
    ----------
    names : tuple of str
        Region names (the mesh's physical surfaces), in the order of ``state["region"]``.
    materials : tuple of Material
        Each region's skeleton.
    permeability : tuple of float
        Each region's k (k_ref of the case's permeability law) [m/s].
    """

    names: tuple
    materials: tuple
    permeability: tuple

    @property
    def plastic(self):
        """True when some region's model yields."""
        return any(m.plastic for m in self.materials)

    @cached_property
    def own_keys(self):
        """Each region's model's state keys (a tuple per region)."""
        return tuple(tuple(m.initial_state(1)[1]) for m in self.materials)

    @cached_property
    def keys(self):
        """The state keys of every region's model, and ``region``."""
        return tuple(sorted({k for keys in self.own_keys for k in keys})) + ("region",)

    def region(self, state):
        """(n,) int: each point's region, from its state."""
        return np.rint(state["region"]).astype(int)

    def gather(self, parts, region):
        """Stress (n, 4) and state of n points from each region's ``(stress, state)``
        of its own points, in region order (the inverse of splitting by ``region``)."""
        n = len(region)
        stress, state = np.empty((n, 4)), {k: np.zeros(n) for k in self.keys}
        for r, (s, st) in enumerate(parts):
            at = region == r
            stress[at] = s
            for k, v in st.items():
                state[k][at] = v
        state["region"] = region.astype(float)
        return stress, state

    def initial_state(self, n, p=None, region=None):
        """Each region's :meth:`initial_state` at its points; ``region`` (n,) int is
        needed (the points' regions, from the mesh)."""
        if region is None:
            raise TypeError("Regions.initial_state needs region, the points' regions")
        region = np.asarray(region, int)
        return self.gather([m.initial_state(int(np.sum(region == r)), p)
                            for r, m in enumerate(self.materials)], region)

    def update(self, stress, state, dstrain, dspin):
        """Each region's model's update on its own points; the tangents gathered."""
        region = self.region(state)
        tangent = np.empty((len(region), 4, 4))
        parts = []
        for r, (m, keys) in enumerate(zip(self.materials, self.own_keys)):
            at = region == r
            own = {k: state[k][at] for k in keys}
            s, st, C = m.update(stress[at], own, dstrain[at], dspin[at])
            tangent[at] = C
            parts.append((s, st))
        new, new_state = self.gather(parts, region)
        return new, new_state, tangent

    def admissible(self, stress, state):
        """Each region's :meth:`admissible` on its own points."""
        region = self.region(state)
        parts = []
        for r, (m, keys) in enumerate(zip(self.materials, self.own_keys)):
            at = region == r
            parts.append((stress[at], m.admissible(stress[at],
                                                   {k: state[k][at] for k in keys})))
        return self.gather(parts, region)[1]

    def k0_nc(self):
        """Not one value: each region's model has its own
        (:mod:`soilwater.physics.geostatic` asks them)."""
        raise TypeError("Regions.k0_nc: ask each region's material (Regions.materials)")

    def moduli(self, p=None, v=None):
        """The largest of the regions' moduli ``(K, G)`` at p' and v (each region's own
        initial state by default): the stiffest region's, the bound that the residual
        scales and the penalty and Nitsche factors read
        (:class:`soilwater.physics.scales.Scales`)."""
        K, G = zip(*(m.moduli(p, v) for m in self.materials))
        return np.maximum.reduce(np.broadcast_arrays(*K)), np.maximum.reduce(
            np.broadcast_arrays(*G))


def fluid_at(fluid, material, state):
    """The pore fluid at the points of ``state``: ``fluid`` itself, or, when
    ``material`` is :class:`Regions`, with each point's region's permeability (an (n,)
    array) [m/s]."""
    if not isinstance(material, Regions):
        return fluid
    return replace(fluid, permeability=np.asarray(material.permeability)[
        material.region(state)])
