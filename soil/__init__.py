"""Shared soil physics: materials, kinematics, stress-point driver, problem definitions.

Nothing in :mod:`soil` knows about a discretisation; both solvers build on it.
Conventions: Cauchy stress, tension positive, stored as
``(xx, yy, zz, xy)``; strain increments in Voigt form ``(xx, yy, zz, 2xy)``
(engineering shear); reported p', q and p_w are compression positive.
"""

from soil.errors import ConvergenceError, InputError, SoilwaterError

__all__ = ["ConvergenceError", "InputError", "SoilwaterError"]
