"""EFG's settings in a case (``[efg]``): the MLS weight names and :class:`EFGSettings`.

A case names an MLS weight by a string; :meth:`Weight.parse` reads it once, when the case
is loaded, into a :class:`Weight` (a canonical name, an integer kind code and the
parameter C). :class:`EFGSettings` holds two of them, for u and p_w, with the other
meshless settings. The grammar of the names (:func:`weight_form`: the families, the
aliases ``Q``, ``E-A``, ``E-B`` and the range :data:`EXP_C` of C) lives here, free of
numba, so that load-time validation (:mod:`soilwater.case.validation`) and the solver
accept exactly the same names; :mod:`soilwater.efg.weights` evaluates the weights from the
kind codes :data:`QUARTIC`, :data:`CUBIC` and :data:`EXPONENTIAL`.
"""

import math
from dataclasses import dataclass, fields

from soilwater.errors import require

QUARTIC, CUBIC, EXPONENTIAL = 0, 1, 2
"""Integer kind codes of the weight families (read by the numba kernels of
soilwater.efg.weights)."""
KIND_CODES = {"quartic": QUARTIC, "cubic": CUBIC, "exp": EXPONENTIAL}
"""Kind code of each weight family."""
WEIGHT_ALIASES = {"q": "quartic", "e-a": "exp:0.5", "e-b": "exp:0.25"}
EXP_C = (1e-3, 1e3)
"""Accepted range of the parameter C of the exponential weight ``exp:C``."""
WEIGHT_FORMS = (f"quartic (alias Q), cubic, exp:C with {EXP_C[0]:g} <= C <= {EXP_C[1]:g} "
                "(E-A = exp:0.5, E-B = exp:0.25)")
#: Default MLS support scale factor of u and p_w (support = scale x distance to the 8th
#: nearest node).
DEFAULT_SCALE = 1.3
CELLS = ("delaunay", "squares")
"""Background integration cells of ``efg.cells``."""
INTEGRATIONS = ("paper", "gauss", "nodal")
"""Where ``efg.integration`` keeps the material state: ``paper``, on the nodes, taken to
the Gauss points of cells rebuilt each step by MLS interpolation and updated at the nodes
after each step (the paper's scheme); ``gauss``, at the Gauss points of Delaunay
triangles of the nodes moved with them, where equilibrium is integrated, rebuilt when
their quality falls below ``rebuild_quality`` with a state transfer and a
re-equilibration (:mod:`soilwater.efg.rebuild`); ``nodal``, on the nodes as the
integration points of stabilised conforming nodal integration
(:mod:`soilwater.efg.smoothing`), whose triangles are rebuilt when their quality falls
below ``rebuild_quality``."""
#: Default ``efg.rebuild_quality``: the FEM re-meshing's threshold (``fem.remesh_quality``).
REBUILD_QUALITY = 0.3
ESSENTIAL = ("penalty", "nitsche")
"""Essential conditions of ``efg.essential``: penalty (:mod:`soilwater.efg.boundary`) or Nitsche's
method (:mod:`soilwater.efg.essential.nitsche`)."""
CORRECTIONS = ("vci", "none")
"""Test-gradient corrections of ``efg.correction``."""
STABILISATIONS = ("none", "perturbation", "projection")
"""Pressure stabilisations of ``efg.stabilisation``: none, the flow-equation perturbation
(:attr:`soilwater.physics.scales.Scales.perturbation`) or the polynomial pressure projection on the
background cells (:attr:`soilwater.physics.scales.Scales.projection`)."""


def weight_form(name, key=None):
    """The family and parameter of an MLS weight name: the grammar of weight names.

    Parameters
    ----------
    name : str
        ``quartic``, ``cubic`` or ``exp:C`` (see :data:`EXP_C`), case-insensitive,
        surrounding blanks ignored; aliases ``Q``, ``E-A`` (``exp:0.5``) and ``E-B``
        (``exp:0.25``).
    key : str, optional
        The case entry holding the name (e.g. ``efg.weight_u``), for the message.

    Returns
    -------
    family : str
        ``"quartic"``, ``"cubic"`` or ``"exp"``.
    c : float
        The parameter C of ``exp:C`` (0 for the splines).

    Raises
    ------
    InputError
        For any other name, listing the valid forms.

    Examples
    --------
    >>> weight_form(" E-B "), weight_form("Q")
    (('exp', 0.25), ('quartic', 0.0))
    >>> weight_form("exp:0", "efg.weight_p")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: efg.weight_p = 'exp:0' is unknown: use quartic (alias Q), ...
    """
    text = str(name).strip().lower()
    text = WEIGHT_ALIASES.get(text, text)
    if text in ("quartic", "cubic"):
        return text, 0.0
    head, _, value = text.partition(":")
    try:
        c = float(value) if head == "exp" else math.nan
    except ValueError:
        c = math.nan
    label = f"weight {name!r}" if key is None else f"{key} = {name!r}"
    require(EXP_C[0] <= c <= EXP_C[1], f"{label} is unknown: use {WEIGHT_FORMS}")
    return "exp", c


@dataclass(frozen=True)
class Weight:
    """An MLS weight function: canonical ``name``, integer ``kind`` code and parameter ``c``.

    ``name`` is ``quartic``, ``cubic`` or ``exp:C``, with C written in the shortest
    ``%g`` form that reads back to ``c`` exactly (``repr`` otherwise), so that the name
    alone identifies the weight: ``str(weight)`` is the name, and two weights parsed from
    equivalent names (``Q`` and ``quartic``, ``E-A`` and ``exp:0.50``) compare equal.
    Evaluate it with :func:`soilwater.efg.weights.evaluate`.

    Examples
    --------
    >>> Weight.parse("E-B")
    Weight(name='exp:0.25', kind=2, c=0.25)
    >>> Weight.parse("Q") == Weight.parse(" quartic "), str(Weight.parse("exp:1e3"))
    (True, 'exp:1000')
    """

    name: str
    kind: int
    c: float = 0.0

    @classmethod
    def parse(cls, name, key=None):
        """The weight a name denotes (a Weight passes through).

        Parameters
        ----------
        name : str or Weight
            A name of the grammar of :func:`weight_form`.
        key : str, optional
            The case entry holding the name (e.g. ``efg.weight_u``), for the message.

        Raises
        ------
        InputError
            For any other name, listing the valid forms.
        """
        if isinstance(name, cls):
            return name
        family, c = weight_form(name, key)
        if family != "exp":
            return cls(family, KIND_CODES[family])
        short = f"{c:g}"
        return cls(f"exp:{short if float(short) == c else repr(c)}", EXPONENTIAL, c)

    def __str__(self):
        return self.name


QUARTIC_WEIGHT = Weight("quartic", QUARTIC)
"""The default weight of u and p_w."""

#: The paper's configuration: the state on the nodes, taken to Gauss points of Delaunay
#: cells rebuilt every step (``integration = "paper"``), penalty essential conditions and
#: no pressure stabilisation. Method ``efg-paper`` runs it, to reproduce the paper.
PAPER = {"integration": "paper", "essential": "penalty", "stabilisation": "none"}
#: The recommended configuration, the defaults of :class:`EFGSettings` and of method
#: ``efg``: the state at the Gauss points of Lagrangian Delaunay cells (consistent and
#: first order in dt), Nitsche's essential conditions (3-5 times closer to fem-th than
#: penalty on the footing) and the flow-equation perturbation (the only pressure
#: stabilisation that passes the inf-sup test on these points). The measurements behind
#: the choice are in the docs' EFG theory page ("The recommended configuration").
RECOMMENDED = {"integration": "gauss", "essential": "nitsche", "stabilisation": "perturbation"}
#: The named configurations: the settings each fixes (the others are the case's).
CONFIGURATIONS = {"recommended": RECOMMENDED, "paper": PAPER}


def configuration(settings):
    """The name of the configuration ``settings`` are in, or ``"custom"``.

    Parameters
    ----------
    settings : EFGSettings

    Returns
    -------
    str
        ``"recommended"`` when the settings have every value of :data:`RECOMMENDED`,
        else ``"paper"`` when they have every value of :data:`PAPER`, else ``"custom"``
        (the recommended name wins when the two coincide).

    Examples
    --------
    >>> configuration(EFGSettings())
    'recommended'
    >>> configuration(EFGSettings(**{**PAPER, "essential": "nitsche"}))
    'custom'
    """
    for name, values in CONFIGURATIONS.items():
        if all(getattr(settings, key) == value for key, value in values.items()):
            return name
    return "custom"


def check(settings):
    """Refuse the combinations of settings no EFG scheme can take, in one line each.

    Checked when an EFG method starts to solve, not when a case loads, so that method
    ``efg-paper`` can take a case written for the paper's scheme (``efg.cells =
    "squares"``) whose defaults are the recommended ones.

    Raises
    ------
    InputError
        ``efg.cells = "squares"`` with a scheme other than ``paper`` (``gauss`` and
        ``nodal`` integrate on the nodes' own triangles), or ``efg.stabilisation =
        "projection"`` with ``nodal`` (one point per cell: nothing to project).

    Examples
    --------
    >>> check(EFGSettings(integration="gauss", cells="squares"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: efg.cells = "squares" needs efg.integration = "paper" ...
    """
    require(settings.integration == "paper" or settings.cells == "delaunay",
            f"efg.cells = \"{settings.cells}\" needs efg.integration = \"paper\" (the "
            f"\"{settings.integration}\" scheme integrates on the nodes' own triangles): "
            "use efg.cells = \"delaunay\" or method efg-paper")
    require(settings.integration != "nodal" or settings.stabilisation != "projection",
            "efg.stabilisation = \"projection\" has nothing to project with "
            "efg.integration = \"nodal\" (one point per cell): use \"perturbation\"")


def departures(settings, name="recommended"):
    """The settings that differ from a named configuration, as ``key = value`` strings.

    Examples
    --------
    >>> departures(EFGSettings(**{**PAPER, "essential": "nitsche"}), "paper")
    ['essential = nitsche (paper: penalty)']
    """
    return [f"{key} = {getattr(settings, key)} ({name}: {value})"
            for key, value in CONFIGURATIONS[name].items() if getattr(settings, key) != value]


@dataclass(frozen=True)
class EFGSettings:
    """Meshless settings: MLS weight and support scale factor for u and p_w, cells, penalty.

    ``weight_u`` and ``weight_p`` are :class:`Weight` objects (a name given instead is
    read by :meth:`Weight.parse`); ``scale_u`` and ``scale_p`` are the support scale
    factors (support = scale x distance to the 8th nearest node, dimensionless);
    ``integration`` is where the material state lives (:data:`INTEGRATIONS`);
    ``rebuild_quality`` is the :func:`soilwater.geometry.quality.cell_quality` below which
    the triangles of ``nodal`` and ``gauss`` are re-triangulated (Delaunay on the current
    nodes) after a converged step; ``gauss`` then carries its Gauss-point state to the new
    triangles (:func:`soilwater.fem.transfer.transfer`) and re-equilibrates it with no
    time increment (:mod:`soilwater.efg.rebuild`) (dimensionless, 0 to 1);
    ``cells`` is ``delaunay`` (rebuilt every step) or ``squares`` (quarter cells along
    the boundary), with ``integration = "paper"``; ``order`` is the Gauss order of the
    cells; ``essential`` is how
    essential conditions are imposed, ``penalty`` (:mod:`soilwater.efg.boundary`) or ``nitsche``
    (:mod:`soilwater.efg.essential.nitsche`: consistent, beta from an eigenvalue bound, no factor to
    choose); ``penalty`` is the penalty factor relative to the stiffness scale (P-wave
    modulus over nodal spacing; unused with ``nitsche``);
    ``correction`` is ``vci`` (variationally consistent test-function gradients, which
    pass the patch test with any quadrature; :mod:`soilwater.efg.vci`) or ``none`` (plain Gauss
    quadrature of the MLS gradients, as in the paper); ``stabilisation`` is ``none``,
    ``perturbation``, the flow-equation term of Aguilar et al. (2008) that
    ``fem-p1p1-stab`` adds, on the MLS pressure (:mod:`soilwater.physics.weakform`), coefficient
    ``h^2 / (4 M)``, or ``projection``, the polynomial pressure projection of Dohrmann
    and Bochev (2004) on the background cells (:func:`soilwater.physics.weakform.fluctuation`),
    coefficient ``1 / G``; ``stabilisation_factor`` (dimensionless) multiplies either.

    Examples
    --------
    >>> settings = EFGSettings(weight_p="E-A")
    >>> settings.weight_p, settings.to_dict()["weight_p"]
    (Weight(name='exp:0.5', kind=2, c=0.5), 'exp:0.5')
    """

    weight_u: Weight = QUARTIC_WEIGHT
    scale_u: float = DEFAULT_SCALE
    weight_p: Weight = QUARTIC_WEIGHT
    scale_p: float = DEFAULT_SCALE
    integration: str = RECOMMENDED["integration"]
    rebuild_quality: float = REBUILD_QUALITY
    cells: str = "delaunay"
    order: int = 2
    essential: str = RECOMMENDED["essential"]
    penalty: float = 1e6
    correction: str = "vci"
    stabilisation: str = RECOMMENDED["stabilisation"]
    stabilisation_factor: float = 1.0

    def __post_init__(self):
        for field in ("weight_u", "weight_p"):
            object.__setattr__(self, field, Weight.parse(getattr(self, field),
                                                         f"efg.{field}"))

    def to_dict(self):
        """The settings as a plain dict, weights by their canonical names."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return {k: str(v) if isinstance(v, Weight) else v for k, v in values.items()}
