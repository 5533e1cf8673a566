"""soilwater: EFG and FEM side by side on finite-strain soil-water coupled problems.

Conventions: Cauchy stress, tension positive, stored as ``(xx, yy, zz, xy)``; strain
increments in Voigt form ``(xx, yy, zz, 2xy)`` (engineering shear); reported p', q and p_w
are compression positive.
"""

from soilwater.errors import ConvergenceError, InputError, SoilwaterError

__all__ = ["ConvergenceError", "InputError", "SoilwaterError"]
