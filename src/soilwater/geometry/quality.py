"""Shape quality of mesh and background cells: the smallest interior
angle and a normalised shape measure of every cell, vectorised over cells.

Both solvers report the worst cell of each level in their history (``min_angle``,
``min_quality``, :func:`soilwater.nonlinear.history.history_row`): the FEM reference on its moved
mesh,
EFG on the background cells it integrates on.
"""

import numpy as np

#: Fraction of its undeformed smallest angle below which an element counts as distorted,
#: and an FEM mesh as no longer to be trusted: a stated threshold, not a measured one
#: (45 to 15 degrees for the triangles of a regular grid; mesh generators that guarantee
#: quality, Shewchuk's Triangle, keep every angle above 20 to 33 degrees). Relative to
#: each element's own start, so that a grid of long cells by design is not distorted.
DISTORTED = 1 / 3
#: Quality of the right isosceles triangle, ``4 sqrt(3) (1/2) / (1 + 1 + 2)``: a square's
#: corner triangles; it scales a quadrilateral's corner values so that a square is 1.
RIGHT_ISOSCELES = np.sqrt(3) / 2


def cell_quality(cells):
    """Smallest interior angle and shape quality of each triangle or quadrilateral.

    Parameters
    ----------
    cells : array_like, shape (C, V, 2)
        Vertex coordinates of C cells [m], counter-clockwise in their undeformed state;
        V = 3 (triangles) or 4 (quadrilaterals).

    Returns
    -------
    angle : ndarray, shape (C,)
        Smallest corner angle of each cell [degrees]. Signed: the angle at a corner is
        ``atan2(cross, dot)`` of its two edges, in (-180, 180], so a corner that turns
        clockwise (an inverted triangle, a reflex or bow-tied quadrilateral, where a
        bilinear map's Jacobian is not positive) is negative. 60 for the equilateral
        triangle, 90 for the square.
    quality : ndarray, shape (C,)
        Triangles: ``4 sqrt(3) A / (l1^2 + l2^2 + l3^2)`` with the signed area A, 1 for
        the equilateral triangle, 0 degenerate, negative inverted. Quadrilaterals: the
        smallest of the values of its four corner triangles (a corner and its two
        neighbours) over that of the right isosceles triangle (:data:`RIGHT_ISOSCELES`),
        so a square is 1 and an inverted or bow-tied quadrilateral negative.

    Examples
    --------
    >>> angle, quality = cell_quality([[[0, 0], [1, 0], [0.5, np.sqrt(3) / 2]],
    ...                                [[0, 0], [1, 0], [0, 1]]])
    >>> np.round(angle, 9).tolist(), np.round(quality, 9).tolist()
    ([60.0, 45.0], [1.0, 0.866025404])
    >>> cell_quality([[[0, 0], [1, 0], [1, 1], [0, 1]]])
    (array([90.]), array([1.]))
    """
    cells = np.asarray(cells, dtype=float)
    if cells.ndim != 3 or cells.shape[1] not in (3, 4) or cells.shape[2] != 2:
        raise ValueError(f"cells: shape {cells.shape} must be (C, 3 or 4, 2) [m]")
    after = np.roll(cells, -1, axis=1) - cells    # edge to the next vertex, (C, V, 2)
    before = np.roll(cells, 1, axis=1) - cells    # edge to the previous vertex
    cross = after[..., 0] * before[..., 1] - after[..., 1] * before[..., 0]  # 2 x area
    dot = np.einsum("cvd,cvd->cv", after, before)
    angle = np.degrees(np.arctan2(cross, dot)).min(axis=1)
    opposite = before - after
    squares = (np.einsum("cvd,cvd->cv", after, after)
               + np.einsum("cvd,cvd->cv", before, before)
               + np.einsum("cvd,cvd->cv", opposite, opposite))
    with np.errstate(invalid="ignore", divide="ignore"):
        corner = np.where(squares > 0, 2 * np.sqrt(3) * cross / squares, 0.0)
    if cells.shape[1] == 3:
        return angle, corner.min(axis=1)  # the three corners are one triangle
    return angle, corner.min(axis=1) / RIGHT_ISOSCELES
