"""The closed-form 2 x 2 determinant and inverse of the hot paths agree with LAPACK's."""

import numpy as np
from hypothesis import given, strategies as st
from hypothesis.extra.numpy import arrays

from soilwater.material.kinematics import determinant, inverse

entries = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


@given(arrays(float, st.tuples(st.integers(0, 5), st.integers(1, 3), st.just(2),
                               st.just(2)), elements=entries))
def test_determinant_and_inverse_match_lapack(A):
    with np.errstate(divide="ignore"):             # LAPACK's det of a singular matrix
        det = np.linalg.det(A)
    np.testing.assert_allclose(determinant(A), det, rtol=1e-10,
                               atol=1e-10 * np.abs(A).max(initial=1.0) ** 2)
    regular = np.abs(det) > 1e-6 * np.abs(A).max(axis=(-2, -1)) ** 2
    B = A[regular]
    np.testing.assert_allclose(inverse(B) @ B, np.broadcast_to(np.eye(2), B.shape),
                               atol=1e-8)
