"""Stress-point driver against closed forms and peer single-point data."""

import numpy as np
import pandas as pd
import pytest

from conftest import table1
from soil.camclay import CamClay
from soil.driver import TESTS, Segment, closed_form_q, integrate, run_test
from soil.errors import InputError


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


def load_geos(peer):
    data = np.loadtxt(peer / "geos_mcc_oedometric_triaxialdriver.txt")
    axial, radial = -data[:, 4], -data[:, 5]
    return -data[:, 1], (axial + 2 * radial) / 3, np.abs(axial - radial)


def test_geos_oedometer_load_unload_reload(peer):
    """GEOS MCC oedometer (peer-data case C) with our hypoelastic variant.

    kappa = C_r v0 and lambda = C_c v0 give K = p'/C_r; G = mu = 5e7 constant. The README
    allows 3 % on the stresses for a hypoelastic variant; unload/reload must be elastic.
    """
    eps_a, p_ref, q_ref = load_geos(peer)
    v0 = 2.0
    clay = CamClay(lam=0.003 * v0, kappa=0.002 * v0, M=1.2, nu=0.25, e0=v0 - 1, p0=1e5,
                   ocr=1.5, model="modified", G=5e7)
    table = run_test(clay, "oedometer", 0.006, points=200)
    np.testing.assert_allclose(table.eps_a, eps_a, atol=1e-12)
    axial = table.p + 2 / 3 * table.q
    radial = table.p - 1 / 3 * table.q
    assert np.abs(axial / (p_ref + 2 / 3 * q_ref) - 1).max() < 0.03
    assert np.abs(radial / (p_ref - 1 / 3 * q_ref) - 1).max() < 0.03
    pc = table.pc.to_numpy()
    assert np.ptp(pc[40:81]) == 0 and np.ptp(pc[120:161]) == 0  # t in [1, 2] and [3, 4]
    assert pc[-1] > pc[40] > clay.ocr * clay.p0


def test_mfront_drained_triaxial(peer):
    """MFront/OGS MCC stress-controlled triaxial (peer-data case B), a different variant.

    Started from the file's state at t = 0.02 (isotropic 2e5 Pa), our hypoelastic law with
    G = E/(2(1+nu)) constant; strains are logarithmic on our side. README tolerance for a
    different variant: 5 % on eps_zz and 2 % on p_c up to t = 0.8. Before t = 0.2 the
    axial strain is mostly elastic and the two elastic laws differ (K = v p'/kappa against
    a constant E), so eps_zz is compared from t = 0.2.
    """
    ref = pd.read_csv(peer / "mfront_ogs_mcc_drained_triax.ref", comment="#", sep=r"\s+",
                      header=None).to_numpy()
    start = int(np.argmin(np.abs(ref[:, 0] - 0.02)))
    row, ref = ref[start], ref[start:]
    clay = CamClay(lam=0.077, kappa=0.0066, M=1.2, nu=0.3, e0=row[23] - 1, p0=2e5,
                   ocr=row[20] / 2e5, model="modified", G=52e6 / 2.6)
    rate = (ref[-1, 9] - row[9]) / (ref[-1, 0] - row[0])
    seg = Segment(ref[-1, 0] - row[0], stress_control=(True, True, True, False),
                  stress_rate=(0.0, rate, 0.0, 0.0))
    raw = integrate(clay, row[7:11][[0, 2, 1, 3]], {"pc": row[20], "v": row[23]}, [seg],
                    points_per_segment=len(ref) - 1)
    t = raw.t.to_numpy() + row[0]
    np.testing.assert_allclose(t, ref[:, 0], atol=1e-9)
    window = (t >= 0.2 - 1e-9) & (t <= 0.8 + 1e-9)
    ezz_ref = ref[:, 3] - row[3]
    rel = np.abs(raw.eyy.to_numpy() - ezz_ref) / np.abs(ezz_ref).clip(1e-300)
    assert rel[window].max() < 0.05
    pc_rel = np.abs(raw.pc.to_numpy() / ref[:, 20] - 1)
    assert pc_rel[t <= 0.8 + 1e-9].max() < 0.02
