"""The gyro's discrepancy loop: nothing named on an effect-free session, a hidden effect named and
refitted, a candidate the motions cannot test called not identifiable with what it needs, and a gyro
that cannot be calibrated reported in one line while the accelerometer's loop still runs (the
tests on the reproductions' simulated sessions: tests/test_repro_gyro_loop.py)."""

from __future__ import annotations

import numpy as np

from accelcal.discrepancy import gyro_loop as GL


def test_small_turns_leave_the_asymmetry_untestable_and_say_what_they_need():
    """Eight turns of 3 deg: no axis turns 30 deg both ways, so the scale asymmetry cannot be
    tested; the row says so, names the axes, and the motions it would need.  Without the
    accelerometer samples the g-sensitivity cannot be formed: not identifiable, never untested."""
    from accelcal.gyro.simulate import simulate_session

    rng = np.random.default_rng(5)
    ses = simulate_session(rng, n_motions=8, angle_deg=3.0, peak_rate_dps=20.0, gyro_noise=1e-3,
                           direction_noise=1e-3)
    gm = GL.GyroMotions(ses.data, ses.C, "magnus4", None, 1.0, False)
    res = GL.gyro_discrepancy(gm, n_boot=99)
    row = res.rounds[0]["scale_asymmetry"]
    assert row["status"] == "not_identifiable" and row["axes_lacking"] == ["x", "y", "z"]
    assert "both ways" in row["needs"]
    assert res.rounds[0]["g_sensitivity"]["status"] == "not_identifiable"
    assert res.outcome == "not_identifiable" or res.named


def test_the_motions_alone_give_the_same_residuals():
    from accelcal.gyro.simulate import simulate_session
    from accelcal.gyro.fit import motion_residuals

    ses = simulate_session(np.random.default_rng(5), n_motions=8, angle_deg=90.0, peak_rate_dps=100.0)
    idx, small = GL.compact(ses.data)
    assert len(idx) < len(ses.data.y)
    np.testing.assert_array_equal(motion_residuals(small, ses.C, "magnus4"), motion_residuals(ses.data, ses.C, "magnus4"))


def test_too_few_bootstrap_draws_to_name_anything_is_said():
    from accelcal.gyro.simulate import simulate_session

    ses = simulate_session(np.random.default_rng(5), n_motions=12, angle_deg=90.0, peak_rate_dps=100.0)
    gm = GL.GyroMotions(ses.data, ses.C, "magnus4", None, 1.0, False)
    assert not GL.gyro_discrepancy(gm, n_boot=999).notes
    note = GL.gyro_discrepancy(gm, n_boot=59).notes
    assert len(note) == 1 and note[0].startswith("59 bootstrap draws cannot name anything")


