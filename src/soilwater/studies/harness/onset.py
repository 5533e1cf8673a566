"""The material's own loss of ellipticity along the stress-point driver's path, and the
linear solvers an ensemble runs with: shared by the uniqueness and shear-band studies."""

import numpy as np
import pandas as pd

from soilwater.case.loader import load_case
from soilwater.diagnostics.bifurcation import ellipticity
from soilwater.linalg.backends import available
from soilwater.material.driver import continuum_path
from soilwater.material.kinematics import in_plane, invariants, spatial_tangent


def continuum_onset(case="unconfined-compression", strain=0.2, points=400):
    """Rudnicki-Rice indicator along the driver's undrained plane-strain path of a case.

    The specimen's homogeneous state has a free lateral surface (total ``sigma_xx = 0``),
    so the total stress is ``sigma' - sigma'_xx I``.

    Returns
    -------
    pandas.DataFrame
        ``strain`` (axial, logarithmic), ``eta_over_M`` (q / (M p')), ``indicator``
        (:func:`soilwater.diagnostics.bifurcation.ellipticity` over the initial P-wave modulus) and
        ``band_angle``: the band normal's inclination from the x axis folded to 0-90
        degrees (the bands at +a and -a are mirror images).
    """
    clay = load_case(case).material()
    raw, tangents = continuum_path(clay, "undrained-plane-strain", strain, points)
    effective = raw[["sxx", "syy", "szz", "sxy"]].to_numpy()
    total = effective - effective[:, :1] * np.array([1.0, 1.0, 1.0, 0.0])
    value, angle = ellipticity(spatial_tangent(tangents, in_plane(effective),
                                               in_plane(total)))
    p, q = invariants(effective)
    return pd.DataFrame({"strain": -raw.eyy.to_numpy(), "eta_over_M": q / (clay.M * p),
                         "indicator": value / clay.constrained_modulus(),
                         "band_angle": np.minimum(angle, 180.0 - angle)})


def solvers():
    """The linear solvers of the ensemble: SuperLU, and PARDISO where it is installed."""
    return ("superlu", "pardiso") if available("pardiso") else ("superlu",)
