"""The FEM reference's settings in a case (``[fem]``): re-meshing for large deformation."""

from dataclasses import dataclass, fields

REMESH = ("never", "delaunay")
"""Re-meshing of the FEM reference, ``fem.remesh``: never (the initial topology throughout)
or the Delaunay triangles of the current vertices (:mod:`soilwater.geometry.triangulation`)."""
REMESH_QUALITY = 0.3
"""Default ``fem.remesh_quality``: about the :func:`soilwater.geometry.quality.cell_quality` of a
triangle
with a 10 degree corner (a right triangle 0.296) or a 150 degree one (the isosceles
triangle 0.302), the angles that mesh generators keep their triangles away from; the
undeformed grid's right isosceles triangles have 0.866."""


@dataclass(frozen=True)
class FEMSettings:
    """Settings of the FEM reference: re-meshing for large deformation.

    ``remesh`` is ``never`` or ``delaunay``: after every converged step whose worst
    element has a :func:`soilwater.geometry.quality.cell_quality` below ``remesh_quality``
    (dimensionless, in (0, 1]; 1 re-triangulates after every step), the current
    vertices are re-triangulated (Delaunay, inside the current boundary polygon) and the
    state at the quadrature points is carried over (:mod:`soilwater.fem.transfer`).
    Triangle pairs only.

    Examples
    --------
    >>> FEMSettings().to_dict()
    {'remesh': 'never', 'remesh_quality': 0.3}
    """

    remesh: str = "never"
    remesh_quality: float = REMESH_QUALITY

    def to_dict(self):
        """The settings as a plain dict."""
        return {f.name: getattr(self, f.name) for f in fields(self)}
