"""Single-point peer data through the driver, with the tolerances for a variant that the
peer data's own README states (``../shared/peer-data/README.md``, outside this repository;
docs/studies/measured.rst lists them)."""

import numpy as np

from soilwater.studies.peers.study import (geos_oedometer, mfront_triaxial,
                                           relative_difference, summary)


def test_geos_oedometer_load_unload_reload(peer):
    """Stresses within 3 % (peer-data README, hypoelastic variant); p'c frozen while
    unloading."""
    frame = geos_oedometer(peer)
    np.testing.assert_allclose(frame.eps_a, frame.eps_a_ref, atol=1e-12)
    assert relative_difference(frame, "axial").max() < 0.03
    assert relative_difference(frame, "radial").max() < 0.03
    pc = frame.pc.to_numpy()
    t = frame.t.to_numpy()
    for lo, hi in ((1, 2), (3, 4)):  # unloading branches are elastic
        assert np.ptp(pc[(t >= lo - 1e-9) & (t <= hi + 1e-9)]) == 0
    assert pc[-1] > pc[t <= 1 + 1e-9][-1] > 1.5e5


def test_mfront_drained_triaxial(peer):
    """Peer-data README, different variant: 5 % on the axial strain and 2 % on p'c up to
    t = 0.8.

    Before t = 0.2 the axial strain is mostly elastic and the elastic laws differ
    (K = v p'/kappa against a constant E), so the strain is compared from t = 0.2.
    """
    frame = mfront_triaxial(peer)
    np.testing.assert_allclose(frame.t, frame.t_ref, atol=1e-9)
    window = (frame.t >= 0.2 - 1e-9) & (frame.t <= 0.8 + 1e-9)
    assert relative_difference(frame[window], "eps_axial").max() < 0.05
    assert relative_difference(frame[frame.t <= 0.8 + 1e-9], "pc").max() < 0.02


def test_summary_meets_every_stated_tolerance(peer):
    table = summary(peer)
    checked = table.dropna(subset=["tolerance"])
    assert len(checked) == 5
    assert (checked.max_rel_diff < checked.tolerance).all()
