"""What an FEM run keeps: the case's fixed data (:class:`Model`), the mesh and what
depends on its elements (:class:`Topology`), and the state carried from step to step
(:class:`State`).
"""

from dataclasses import dataclass

import numpy as np

from soilwater.errors import InputError
from soilwater.fem.constraints import Constraints
from soilwater.fem.spaces import Space, cell_bases
from soilwater.physics.scales import Scales


@dataclass
class Model:
    """What stays fixed over a run: case, method, material, initial space, scales, the
    boundary loop (vertex indices, counter-clockwise) that re-meshing keeps, and the
    ``origin`` (N, 2) [m]: the vertices' positions at t = 0, from which displacements are
    measured (the initial mesh's, or where a gravity start left them,
    :mod:`soilwater.nonlinear.gravity_start`)."""

    case: object
    method: str
    material: object
    space: Space
    scales: Scales
    loop: np.ndarray
    origin: np.ndarray

    @classmethod
    def build(cls, case, method):
        if case.analysis != "coupled":
            raise InputError(f"--method {method} solves coupled cases; case {case.name!r}"
                             f" is {case.analysis!r}: use --method efg")
        material = case.material()
        space = Space.build(case, method)
        if case.fem.remesh != "never" and space.pair.shape != "triangle":
            raise InputError(f"fem.remesh = {case.fem.remesh!r} re-triangulates the mesh, "
                             f"--method {method} has quadrilaterals: use fem-th, fem-p1p1 "
                             "or fem-p1p1-stab, or fem.remesh = \"never\"")
        return cls(case, method, material, space, Scales.of(case, material),
                   case.boundary_loop(), space.mesh0.p.T.copy())

    @property
    def beta(self):
        """Stabilisation ``h^2 / (4 M)`` of fem-p1p1-stab [m2/kPa], else 0."""
        return self.scales.perturbation if self.space.pair.stabilised else 0.0


@dataclass
class Topology:
    """A mesh of the run's vertices and what depends on its elements.

    Attributes
    ----------
    space : Space
    constraints : Constraints
    probes : scipy.sparse matrix, shape (P, n_p), or None
        Pressure at each probe (a material point) from the pressure DOFs.
    """

    space: Space
    constraints: object
    probes: object

    @classmethod
    def initial(cls, case, space):
        """The initial mesh, probes located at their initial positions."""
        _, pb = cell_bases(space.mesh0, space.pair)
        points = np.array([p.point for p in case.probes]).reshape(-1, 2)
        return cls(space, Constraints.build(case, space),
                   pb.probes(points.T) if len(points) else None)

    def remeshed(self, case, vertices, triangles):
        """The topology of new triangles (E, 3) on the current ``vertices`` (N, 2) [m]
        (:meth:`soilwater.fem.spaces.Space.remeshed`); the probes' current positions (this
        mesh's interpolation of the vertex positions) are located in the new mesh."""
        space = self.space.remeshed(case, vertices, triangles)
        probes = None
        if self.probes is not None:
            _, pb = cell_bases(space.moved(vertices), space.pair)
            probes = pb.probes((self.probes @ vertices).T)
        return Topology(space, Constraints.build(case, space), probes)


@dataclass
class State:
    """What is carried from step to step (quadrature arrays flattened element-major)."""

    vertices: np.ndarray     # (N, 2) current mesh vertices [m]
    stress: np.ndarray       # (E Q, 4) effective stress, tension positive
    state: dict              # material state at the quadrature points
    p: np.ndarray            # (n_p,) pore pressure DOFs, compression positive
    weights: np.ndarray      # (E Q,) current quadrature weights [m2]
    stretching: np.ndarray   # (E Q, 4) stretching of the last step [1/s]
    velocity: np.ndarray     # (2 n_u,) du/dt of the last step [m/s]: the predictor
    topology: Topology       # the mesh the next step is solved on
    uniqueness: float = 0.0  # the last step's soilwater.diagnostics.bifurcation indicator
    reactions: np.ndarray = None  # (S,) vertical force on the soil per named segment
    remeshes: int = 0        # re-meshings so far
    refused: int = 0         # re-meshings refused so far (not conforming, inadmissible)
    remesh_residual: float = 0.0  # scaled equilibrium residual after the last re-meshing
