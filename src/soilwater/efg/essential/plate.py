"""The rigid plate's settlement and the mean-pressure multiplier in the EFG tangent.

A rigid plate (Mandel) or a load-controlled footing adds one unknown, its settlement,
tied to its boundary points by the essential conditions' method; a confined undrained
body adds a Lagrange multiplier that pins the mean change of p_w
(:attr:`soilwater.physics.scales.Scales.pin_pressure`). :func:`bordered` appends both to
the tangent of ``(ux, uy, p_w)``.
"""

import numpy as np
import scipy.sparse as sp


def bordered(K, plate, c_mean, pin):
    """Append the rigid plate's settlement (``plate``: its column, row and corner, or
    None) and the mean-pressure multiplier (if ``pin``) to the tangent K of ``(ux, uy,
    p_w)``."""
    cols, rows, corner = [], [], []
    n = K.shape[0] // 3
    if plate is not None:
        cols.append(plate[0])
        rows.append(plate[1])
        corner.append(plate[2])
    if pin:
        c = np.zeros(3 * n)
        c[2 * n:3 * n] = c_mean
        cols.append(c)
        rows.append(c)
        corner.append(0.0)
    if not cols:
        return K
    C, B = sp.csc_matrix(np.column_stack(cols)), sp.csr_matrix(np.vstack(rows))
    return sp.bmat([[K, C], [B, sp.diags(corner)]], format="csr")
