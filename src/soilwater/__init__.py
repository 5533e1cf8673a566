"""soilwater: EFG and FEM side by side on finite-strain soil-water coupled problems.

Load a case, solve it with a method, read the result::

    import soilwater

    case = soilwater.load_case("terzaghi", "time.steps=20")   # built-in name or TOML file
    result = soilwater.solve(case, method="efg")               # or "fem-th", ...
    result.history                  # pandas.DataFrame, one row per time step
    result.units                    # {column: unit}
    result.mesh()                   # meshio.Mesh of the last fields

:func:`load_case` and :meth:`Case.replace` validate every change; ``soilwater.METHODS``
lists the methods. ``import soilwater`` loads neither matplotlib nor the studies.

Conventions: Cauchy stress, tension positive, stored as ``(xx, yy, zz, xy)``; strain
increments in Voigt form ``(xx, yy, zz, 2xy)`` (engineering shear); reported p', q and p_w
are compression positive. Units are those of the case: kPa, m, s in the built-in cases.
"""

from soilwater.case.loader import builtin_cases, load_case
from soilwater.case.model import Case
from soilwater.errors import ConvergenceError, InputError, SoilwaterError
from soilwater.methods import METHODS, solve
from soilwater.results import Result

__all__ = ["METHODS", "Case", "ConvergenceError", "InputError", "Result", "SoilwaterError",
           "builtin_cases", "load_case", "solve"]
