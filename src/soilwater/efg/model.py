"""What an EFG run keeps: the case's fixed data (:class:`Model`) and the material points
(:class:`Points`), carried from step to step.

The material points are the nodes with ``efg.integration = "paper"`` or ``"nodal"`` and
the Gauss points of the Delaunay triangles with ``"gauss"`` (the initial ones until a
rebuild) (:data:`soilwater.efg.settings.INTEGRATIONS`).
"""

from dataclasses import dataclass

import numpy as np

from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.geometry.triangulation import delaunay_triangles
from soilwater.physics.geostatic import total_stress
from soilwater.physics.scales import Scales


@dataclass
class Points:
    """The nodes, the material points and everything that is carried from step to step."""

    nodes: np.ndarray        # (N, 2) current coordinates [m]
    stress: np.ndarray       # (P, 4) effective stress at the material points, tension +
    state: dict              # material state at the material points
    p: np.ndarray            # (N,) pore pressure parameters, compression positive
    gap: np.ndarray          # (G, 2) u^h - u_bar at boundary points (constrained parts)
    plate: float             # rigid-plate settlement (uy, m)
    plate_gap: np.ndarray    # (G,) u_y^h - plate at the plate's points
    probes: np.ndarray       # (P, 2) current probe positions
    stretching: np.ndarray   # (P, 4) stretching of the last step at the material points
                             # (paper: the nodal D^I of ERR) [1/s]
    uniqueness: float = 0.0  # the last step's soilwater.diagnostics.bifurcation indicator
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment
    cells: object = None     # soilwater.efg.quadrature.Quadrature on ``nodes`` (next step's)
    rcond: float = np.nan    # smallest MLS rcond at the last step's integration points
    boundary_stress: np.ndarray = None  # (G, 4) at the boundary points ("gauss", Nitsche)
    boundary_state: dict = None         # material state there


@dataclass
class Model:
    """What stays fixed over a run: case, material, boundary topology, scales, and the
    positions at t = 0 from which displacements are measured, of the nodes (``origin``,
    (N, 2) [m]) and of the probes (``probes0``, (P, 2) [m]): the initial ones, or where a
    gravity start left them (:mod:`soilwater.nonlinear.gravity_start`)."""

    case: object
    material: object
    loop: np.ndarray
    edges: np.ndarray
    scales: Scales
    initial_bp: np.ndarray   # (G, 2) boundary points in the initial configuration [m]
    sigma0_bp: np.ndarray    # (G, 4) initial total stress there [kPa]
    triangles: np.ndarray | None = None  # (C, 3) initial triangles ("gauss", "nodal")
    origin: np.ndarray | None = None     # (N, 2) node positions at t = 0 [m]
    probes0: np.ndarray | None = None    # (P, 2) probe positions at t = 0 [m]

    @classmethod
    def build(cls, case):
        material = case.material()
        loop = case.boundary_loop()
        edges = segment_edges(case.nodes(), loop, case.geometry)
        initial_bp = boundary_points(case.nodes(), loop, edges).points
        triangles = None
        if case.geometry.mesh is not None and case.efg.integration != "paper":
            triangles = case.geometry.mesh.triangles
        elif case.efg.integration != "paper":
            nodes = case.nodes()
            triangles, _ = delaunay_triangles(nodes, nodes[loop])
        return cls(case, material, loop, edges, Scales.of(case, material), initial_bp,
                   total_stress(case, material, initial_bp), triangles, case.nodes(),
                   np.array([p.point for p in case.probes]).reshape(-1, 2))

    @property
    def consistent(self):
        """True when the material state lives where equilibrium is integrated (``gauss``
        and ``nodal``): a step starts from the state that satisfied it."""
        return self.triangles is not None

    @property
    def gauss(self):
        """True when the material state lives at the Gauss points of :attr:`triangles`."""
        return self.case.efg.integration == "gauss"

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
