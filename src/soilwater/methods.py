"""The methods, by name, and :func:`solve`: run a case with one of them.

``efg`` is the meshless element-free Galerkin solver (:mod:`soilwater.efg`) with the
case's ``[efg]`` settings, whose defaults are the recommended configuration
(:data:`soilwater.efg.settings.RECOMMENDED`); ``efg-paper`` is the same solver in the
paper's configuration (:data:`soilwater.efg.settings.PAPER`), which reproduces the paper.
Every other method is a scikit-fem element pair of :data:`soilwater.fem.spaces.PAIRS`
(``fem-th``, ``fem-p1p1``, ...). ``soilwater run --method``, the study harness and
:func:`solve` all look methods up here, in :data:`METHODS`.
"""

from os import PathLike

from soilwater.case.loader import load_case
from soilwater.case.model import Case
from soilwater.efg.settings import PAPER, RECOMMENDED, configuration
from soilwater.errors import InputError, require
from soilwater.fem.spaces import PAIRS


def _efg(case, progress=True):
    """EFG: static elasticity for ``analysis = "static"``, else the coupled solver; the
    summary names the configuration (:func:`soilwater.efg.settings.configuration`)."""
    if case.analysis == "static":
        from soilwater.efg.statics import solve

        result = solve(case)
    else:
        from soilwater.efg.solver import solve

        result = solve(case, progress=progress)
    result.summary["configuration"] = configuration(case.efg)
    return result


def paper(case):
    """The case in the paper's EFG configuration: :data:`~soilwater.efg.settings.PAPER`
    over its ``[efg]`` section.

    Raises
    ------
    InputError
        If the case sets one of those settings to a third value (neither the paper's nor
        the recommended one), which ``efg-paper`` would silently replace.

    Examples
    --------
    >>> import soilwater
    >>> paper(soilwater.load_case("terzaghi")).efg.integration
    'paper'
    """
    for key, value in PAPER.items():
        given = getattr(case.efg, key)
        require(given in (value, RECOMMENDED[key]),
                f"efg.{key} = {given!r} is not the paper's: method efg-paper sets it to "
                f"{value!r}; remove it from the case or run method efg")
    return case.replace(*(f"efg.{key}={value}" for key, value in PAPER.items()))


def _efg_paper(case, progress=True):
    """EFG in the paper's configuration (:func:`paper`)."""
    return _efg(paper(case), progress)


def _fem(method):
    """The scikit-fem solver with the element pair ``method``."""
    def solve(case, progress=True):
        from soilwater.fem.solver import solve

        return solve(case, method, progress)

    return solve


#: Solvers by method name, ``(case, progress=True) -> Result``: ``efg``, ``efg-paper``
#: and the FEM pairs.
METHODS = {"efg": _efg, "efg-paper": _efg_paper, **{name: _fem(name) for name in PAIRS}}
#: The methods solved by EFG (:mod:`soilwater.efg`); the others by :mod:`soilwater.fem`.
EFG_METHODS = ("efg", "efg-paper")


def solver(method):
    """The solver of a method name, ``(case, progress=True) -> Result``.

    Raises
    ------
    InputError
        If ``method`` is not one of :data:`METHODS` (the message lists them).

    Examples
    --------
    >>> solver("fem-q9")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: method 'fem-q9' is unknown: use one of efg, efg-paper, fem-th, ...
    """
    if method not in METHODS:
        raise InputError(f"method {method!r} is unknown: use one of {', '.join(METHODS)}")
    return METHODS[method]


def solve(case, method="efg", progress=True):
    """Solve a case with a method and return its :class:`~soilwater.results.Result`.

    Parameters
    ----------
    case : Case or str or Path
        A case (:func:`soilwater.load_case`), or a built-in case name or TOML file, loaded
        without overrides.
    method : str
        ``"efg"``, ``"efg-paper"`` or an FEM pair of :data:`METHODS` (``"fem-th"``, ...).
    progress : bool
        A progress bar over the time steps on the terminal.

    Returns
    -------
    Result
        ``history`` (one row per time step, units in :attr:`Result.units`), the field
        ``snapshots`` (:meth:`Result.mesh`), ``summary`` and the solved ``case``.

    Raises
    ------
    TypeError
        A ``case`` or ``method`` of the wrong type (naming the argument).
    InputError
        An unknown method or a case the method cannot solve (one line naming the fix).
    ConvergenceError
        A step that fails after every halving, unless ``time.on_failure = "stop"``.

    Examples
    --------
    >>> import soilwater
    >>> case = soilwater.load_case("terzaghi", "time.steps=2", "time.end=0.1")
    >>> result = soilwater.solve(case, "efg", progress=False)
    >>> result.history.time.tolist()
    [0.05, 0.1]
    """
    if not isinstance(case, Case):
        if not isinstance(case, (str, PathLike)):
            raise TypeError(f"solve: case must be a Case (soilwater.load_case), a built-in "
                            f"case name or a TOML file's path, not {type(case).__name__}")
        case = load_case(case)
    if not isinstance(method, str):
        raise TypeError(f"solve: method must be a method name ({', '.join(METHODS)}), not "
                        f"{type(method).__name__}")
    return solver(method)(case, progress=progress)
