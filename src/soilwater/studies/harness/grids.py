"""Node sets of the strip-footing studies, as ``discretisation`` overrides of the built-in
``strip-footing`` case.

Both families have equal spacings of ``B / core`` within :data:`CORE` of the footing
(from the symmetry axis to x = 1 m, and 1 m deep), then grow to the far edges, and put a
node on the footing's edge (x = B / 2):

* :func:`refined`: the built-in layout (33 outer spacings growing 3.75-fold on a 10 B
  domain, for ``core = 8``), refined or on another domain with the outer spacings
  growing alike: every cell's aspect stays within about 4, as EFG's isotropic supports
  (the 8th nearest node) need;
* :func:`growing`: spacings growing by a fixed factor per cell from the core to the far
  edges of any domain, the usual mesh of a boundary-value study; its far cells are long
  and flat at the domain's corners, which FEM bears and EFG's supports do not.
"""

import math

from scipy.optimize import brentq

#: Side of the square of equal spacings at the footing [m] (the footing's width B).
CORE = 1.0
#: Growth of the outer spacings (last over first) of :func:`refined`.
OUTER_RATIO = 3.75
#: Growth of neighbouring spacings in :func:`growing`.
GROWTH = 1.15


def refined(core, domain=10.0):
    """Overrides of the built-in layout refined to ``core`` spacings per :data:`CORE`:
    beyond the core, as many spacings as make the first one about ``g`` times the core's
    and the last :data:`OUTER_RATIO` times the first (``g = OUTER_RATIO^(1/(n - 1))``),
    so that no cell is more than about 4 times longer than wide, whatever the domain.

    Examples
    --------
    >>> x, y = refined(8)[2:]
    >>> x
    'discretisation.x=[[1.0, 8], [10.0, 33, 3.75]]'
    >>> y
    'discretisation.y=[[9.0, 33, 0.26666666666666666], [10.0, 8]]'
    >>> [refined(core)[2].split(", ")[3] for core in (4, 12)]
    ['16', '50']
    """
    h, rest, R = CORE / core, domain - CORE, OUTER_RATIO

    def filled(n):
        g = R ** (1 / (n - 1))
        return h * g * (R * g - 1) / (g - 1) - rest
    return _overrides(domain, core, round(brentq(filled, 2, 1e4)), R)


def growing(domain, core=8, growth=GROWTH):
    """Overrides of a ``domain x domain`` [m] layout whose spacings grow by about
    ``growth`` per cell beyond the core (the outer spacings fill the rest exactly).

    Examples
    --------
    >>> growing(10.0)[2]
    'discretisation.x=[[1.0, 8], [10.0, 17, 8.9]]'
    """
    h, rest = CORE / core, domain - CORE
    count = math.ceil(math.log(1 + rest * (growth - 1) / (h * growth)) / math.log(growth))
    g = brentq(lambda g: h * g * (g**count - 1) / (g - 1) - rest, 1 + 1e-9, 2 * growth)
    return _overrides(domain, core, count, round(g ** (count - 1), 1))


def _overrides(domain, core, outer, ratio):
    """Width, height and the pieces along x (core at the left) and y (core at the top)."""
    return (f"geometry.width={domain:g}", f"geometry.height={domain:g}",
            f"discretisation.x=[[{CORE!r}, {core}], [{float(domain)!r}, {outer}, {ratio!r}]]",
            f"discretisation.y=[[{float(domain - CORE)!r}, {outer}, {1 / ratio!r}], "
            f"[{float(domain)!r}, {core}]]")
