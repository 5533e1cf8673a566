"""The strip footing's methods, width and time steps, shared by the footing studies and
the essential-conditions study."""

from soilwater.studies.harness.quick import pick


#: The built-in case of the strip-footing studies.
CASE = "strip-footing"


#: The methods of the study (label: method and overrides): EFG in the recommended
#: configuration (``efg``) and in the paper's (``efg-paper``), the two FEM pairs of the
#: comparison and Taylor-Hood re-meshed when its mesh degrades (``fem.remesh``; P1/P1's
#: elements stay above the re-meshing threshold to 1 B, so it would not re-mesh).
METHODS = {"efg": ("efg", ()), "efg-paper": ("efg-paper", ()),
           "fem-th": ("fem-th", ()), "fem-p1p1-stab": ("fem-p1p1-stab", ()),
           "fem-th+remesh": ("fem-th", ("fem.remesh=delaunay",))}


#: The methods of :data:`METHODS` without overrides, whose labels are their method names
#: (the paper's comparison): the partially drained footing and the pictures run these.
PLAIN = {label: spec for label, spec in METHODS.items() if not spec[1]}


#: Time steps per step of the built-in case: a quick report takes half as many, each
#: twice as long.
STEP_FACTOR = pick(1.0, 0.5)


def time_steps(case, factor=1.0):
    """Time steps of a footing run pushed ``factor`` times the case's settlement: the
    case's steps scaled by ``factor`` and :data:`STEP_FACTOR`."""
    return round(case.time.steps * factor * STEP_FACTOR)


def width(case):
    """Footing width B [m]: twice the segment (the case is the symmetry half)."""
    (_, footing), = case.boundary.segments()
    return 2 * (footing.end - footing.start)
