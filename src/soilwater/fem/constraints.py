"""The exact essential conditions of the FEM reference (:class:`Constraints`).

Fixed and prescribed displacement DOFs and drained pressure DOFs are eliminated; a rigid
plate (or a load-controlled footing) ties every uy DOF of its edge (segment) to one
unknown. The reduced unknowns are ``T`` times the full ones' free part.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp



@dataclass
class Constraints:
    """Exact essential conditions on the unknowns ``[ux (n_u), uy (n_u), p (n_p)]``.

    Attributes
    ----------
    fixed : ndarray of int
        Unknowns with a zero increment (fixed displacement).
    prescribed : ndarray of int
        Displacement unknowns following ``v = L x``; ``component`` is 0 (x) or 1 (y).
    component : ndarray of int
    drained : ndarray of int
        Pressure unknowns held at p_w = 0.
    plate : ndarray of int
        uy unknowns tied to the rigid plate (a ``rigid`` edge or a load-controlled
        footing).
    footing : ndarray of int
        uy unknowns of velocity-controlled footings, moving by ``-rate dt`` per step;
        ``rate`` [m/s, positive down] is each one's settlement rate.
    rate : ndarray
    segment_dofs : list of ndarray of int
        uy unknowns of each named segment (``case.boundary.segments()`` order), whose
        residuals sum to the segment's vertical reaction.
    unloaded : dict
        Per edge name, (F,) bool over its facets: facets on a named segment, which
        carry no edge traction (:meth:`soilwater.case.boundary.Edge.loaded`).
    T : scipy.sparse.csr_matrix
        Full increment = ``T @ reduced``: free unknowns, then the plate (if any).
    is_u : ndarray of bool
        Which reduced unknowns are displacements (the plate included).
    """

    fixed: np.ndarray
    prescribed: np.ndarray
    component: np.ndarray
    drained: np.ndarray
    plate: np.ndarray
    footing: np.ndarray
    rate: np.ndarray
    segment_dofs: list
    unloaded: dict
    T: object
    is_u: np.ndarray

    @classmethod
    def build(cls, case, space):
        """The DOF sets from the kinds at each boundary DOF's initial position (edge and
        named segments, :meth:`soilwater.case.model.Case.edge_conditions`)."""
        n_u = space.n_u
        u_locs, p_locs = space.doflocs0
        sets = {"fixed": [], "prescribed": [], "rigid": [], "footing": []}
        component, drained, rates, segment_dofs, unloaded = [], [], [], [], {}
        rate_of = np.array([seg.settlement_rate if seg.footing else 0.0
                            for _, seg in case.boundary.segments()] + [0.0])
        first = 0
        for name, edge in case.boundary.items():
            dofs = space.u_dofs[name]
            kind, _, seg = case.edge_conditions(name, u_locs[:, dofs].T)
            for f in range(2):
                for k in sets:
                    pick = dofs[kind[:, f] == k]
                    sets[k].append(f * n_u + pick)
                    if k == "prescribed":
                        component.append(np.full(len(pick), f))
                    if k == "footing":
                        rates.append(rate_of[first + seg[kind[:, f] == k]])
            segment_dofs += [n_u + dofs[seg == j] for j in range(len(edge.segments))]
            pdofs = space.p_dofs[name]
            _, wet, _ = case.edge_conditions(name, p_locs[:, pdofs].T)
            drained.append(2 * n_u + pdofs[wet])
            facets = space.edge_facets[name]
            mid = space.mesh0.p[:, space.mesh0.facets[:, facets]].mean(axis=1).T
            unloaded[name] = ~edge.loaded(case.edge_conditions(name, mid)[2])
            first += len(edge.segments)
        fixed, plate, drained = (np.unique(np.concatenate(s)) if s else np.zeros(0, int)
                                 for s in (sets["fixed"], sets["rigid"], drained))
        footing, first_f = np.unique(np.concatenate(sets["footing"]).astype(int),
                                     return_index=True)
        rate = np.concatenate(rates or [[]])[first_f]
        prescribed, first = np.unique(np.concatenate(sets["prescribed"] or [[]]).astype(int),
                                      return_index=True)
        component = np.concatenate(component or [[]]).astype(int)[first]
        n = 2 * n_u + space.n_p
        free = np.setdiff1d(np.arange(n), np.concatenate([fixed, prescribed, drained, plate,
                                                          footing]))
        rows = np.concatenate([free, plate])
        cols = np.concatenate([np.arange(len(free)), np.full(len(plate), len(free))])
        T = sp.csr_matrix((np.ones(len(rows)), (rows, cols)),
                          shape=(n, len(free) + int(len(plate) > 0)))
        is_u = np.append(free < 2 * n_u, np.ones(int(len(plate) > 0), bool))
        return cls(fixed, prescribed, component, drained, plate, footing, rate,
                   segment_dofs, unloaded, T, is_u)
