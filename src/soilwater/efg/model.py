"""What an EFG run keeps: the case's fixed data (:class:`Model`) and the material points
(:class:`Points`), carried from step to step.
"""

from dataclasses import dataclass

import numpy as np

from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.physics.geostatic import total_stress
from soilwater.physics.scales import Scales


@dataclass
class Points:
    """The material points (nodes) and everything that is carried from step to step."""

    nodes: np.ndarray        # (N, 2) current coordinates [m]
    stress: np.ndarray       # (N, 4) effective stress, tension positive
    state: dict              # material state at the nodes
    p: np.ndarray            # (N,) pore pressure parameters, compression positive
    gap: np.ndarray          # (G, 2) u^h - u_bar at boundary points (constrained parts)
    plate: float             # rigid-plate settlement (uy, m)
    plate_gap: np.ndarray    # (G,) u_y^h - plate at the plate's points
    probes: np.ndarray       # (P, 2) current probe positions
    stretching: np.ndarray   # (N, 4) nodal stretching D^I of the last step [1/s]
    uniqueness: float = 0.0  # the last step's soilwater.diagnostics.bifurcation indicator
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment
    cells: object = None     # soilwater.efg.quadrature.Quadrature on ``nodes`` (next step's)
    rcond: float = np.nan    # smallest MLS rcond at the last step's integration points


@dataclass
class Model:
    """What stays fixed over a run: case, material, boundary topology, scales."""

    case: object
    material: object
    loop: np.ndarray
    edges: np.ndarray
    scales: Scales
    initial_bp: np.ndarray   # (G, 2) boundary points in the initial configuration [m]
    sigma0_bp: np.ndarray    # (G, 4) initial total stress there [kPa]

    @classmethod
    def build(cls, case):
        material = case.material()
        loop = case.boundary_loop()
        edges = segment_edges(case.nodes(), loop, case.geometry)
        initial_bp = boundary_points(case.nodes(), loop, edges).points
        return cls(case, material, loop, edges, Scales.of(case, material), initial_bp,
                   total_stress(case, material, initial_bp))

    @property
    def beta(self):
        """Coefficient of the flow-equation perturbation [m2/kPa] with
        ``efg.stabilisation = "perturbation"`` (times ``efg.stabilisation_factor``), else
        0."""
        return self._stabilisation("perturbation")

    @property
    def tau(self):
        """Coefficient of the polynomial pressure projection [1/kPa] with
        ``efg.stabilisation = "projection"`` (times ``efg.stabilisation_factor``), else
        0."""
        return self._stabilisation("projection")

    def _stabilisation(self, kind):
        s = self.case.efg
        if s.stabilisation != kind:
            return 0.0
        return getattr(self.scales, kind) * s.stabilisation_factor
