"""Stress-point driver against closed forms and peer single-point data."""

import numpy as np
import pytest

from conftest import table1
from soilwater.material.driver import TESTS, closed_form_q, run_test
from soilwater.errors import InputError


@pytest.mark.parametrize("model,ocr", [("original", 1.0), ("modified", 1.0), ("modified", 2.0)])
@pytest.mark.parametrize("test", ["undrained-plane-strain", "undrained-simple-shear",
                                  "undrained-triaxial"])
def test_undrained_path_matches_closed_form_up_to_failure(model, ocr, test):
    clay = table1(model, ocr)
    table = run_test(clay, test, 0.3, points=300)
    p, q = table.p.to_numpy(), table.q.to_numpy()
    eta = q / p
    assert eta[-1] > 0.999 * clay.M  # failure reached
    assert np.allclose(table.eps_v, 0, atol=1e-10)  # isochoric
    plastic = (clay.yield_value(_stress(table), {"pc": table.pc.to_numpy()}) > -1e-8) & (q > 0)
    if ocr == 2.0:  # MCC at OCR 2 yields on the critical state line and stays there
        assert np.allclose(p, clay.p0, rtol=1e-9)
        assert np.abs(q[plastic] / (clay.M * clay.p0) - 1).max() < 1e-4
        return
    rel = np.abs(q[plastic] - closed_form_q(clay, p[plastic])) / q[plastic]
    assert rel.max() < 1e-4


def _stress(table):
    """A tension-positive stress with the table's p' and q: deviator q/sqrt(3) (1, -1, 0)."""
    p, q = table.p.to_numpy(), table.q.to_numpy()
    return np.column_stack([-p + q / np.sqrt(3), -p - q / np.sqrt(3), -p, 0 * p])


def test_original_cam_clay_fails_at_the_closed_form_pressure():
    clay = table1()
    table = run_test(clay, "undrained-plane-strain", 0.5)
    assert table.p.iloc[-1] == pytest.approx(clay.p0 * np.exp(-clay.Lambda), rel=1e-6)


def test_isotropic_compression_has_slopes_kappa_and_lambda():
    """ln p' against v: slope -1/kappa when elastic (OCR 2), -1/lambda on the NCL."""
    clay = table1("modified", 2.0)
    table = run_test(clay, "isotropic", 0.1, points=400)
    v = clay.v0 * np.exp(-table.eps_v.to_numpy())
    lnp = np.log(table.p.to_numpy())
    slope = np.diff(v) / np.diff(lnp)
    elastic, virgin = table.p < 0.99 * 2 * clay.p0, table.p > 1.01 * 2 * clay.p0
    assert np.allclose(slope[elastic[1:].to_numpy()], -clay.kappa, rtol=1e-6)
    assert np.allclose(slope[virgin[1:].to_numpy()], -clay.lam, rtol=1e-6)


def test_every_named_test_runs_and_compression_is_positive():
    clay = table1("modified", 1.0)
    for name in TESTS:
        table = run_test(clay, name, 0.05, points=20)
        assert list(table.columns) == ["step", "eps_a", "eps_v", "p", "q", "pc"]
        assert table.eps_a.iloc[-1] == pytest.approx(0.05, rel=1e-9)
        assert np.isfinite(table.to_numpy()).all() and (table.p > 0).all()


def test_unknown_test_is_refused():
    with pytest.raises(InputError, match="unknown driver test"):
        run_test(table1(), "triaxial-extension", 0.1)


@pytest.mark.parametrize("model,ocr", [("original", 1.0), ("modified", 1.0), ("modified", 2.0)])
def test_plane_strain_undrained_strength_is_the_closed_form(model, ocr):
    """At 50 % strain the largest in-plane shear stress (sigma_1 - sigma_3)/2 of isochoric
    plane strain is ``M p'_f / sqrt(3)`` (soilwater.references.closed_forms.undrained_strength): the
    out-of-plane stress has become the in-plane mean."""
    from soilwater.references.closed_forms import undrained_strength
    from soilwater.material.driver import _integrated

    clay = table1(model, ocr)
    raw, _ = _integrated(clay, "undrained-plane-strain", 0.5, 200)
    last = raw.iloc[-1]
    tau = np.hypot((last.sxx - last.syy) / 2, last.sxy)
    assert tau == pytest.approx(undrained_strength(clay), rel=1e-3)
    assert last.szz == pytest.approx((last.sxx + last.syy) / 2, rel=1e-3)
