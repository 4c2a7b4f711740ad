"""The automatic choice of the static-detection settings."""

import numpy as np
import pytest

from accelcal.errors import RecordingError
from accelcal.gyro.simulate import simulate_recording
from accelcal.static import detect_static
from accelcal.static_auto import choose_static, merge_split_rests


def test_short_still_phases_are_found_without_hand_tuning():
    r = simulate_recording(np.random.default_rng(3), n_motions=20, rest_s=1.0, init_rest_s=5.0)
    assert len(detect_static(r["t"], r["acc"])) < 12  # the defaults (1 s window, 1 s minimum) miss them
    choice = choose_static(r["t"], r["acc"], r["g"], unit="m/s^2")
    assert len(choice.poses) == 21  # the initial rest and one pose after each motion
    assert choice.settings["window"] < 1.0
    assert "poses" in choice.describe()


def test_a_rest_split_by_a_tap_is_one_pose_again():
    r = simulate_recording(np.random.default_rng(4), n_motions=12, rest_s=4.0, init_rest_s=10.0)
    acc = r["acc"].copy()
    still = np.flatnonzero(np.linalg.norm(r["rates"], axis=1) == 0)
    tap = still[len(still) // 2]
    acc[tap:tap + 30] += 0.5 * np.random.default_rng(0).standard_normal((30, 3))  # a 0.3 s tap, no rotation
    split = detect_static(r["t"], acc, window=0.3, min_duration=0.3, trim=0.05)
    merged = merge_split_rests(split)
    assert len(merged) == len(split) - 1
    assert len(merged) == 13


def test_no_setting_finds_enough_poses():
    r = simulate_recording(np.random.default_rng(5), n_motions=5)
    with pytest.raises(RecordingError, match="no detection setting finds 12"):
        choose_static(r["t"], r["acc"], r["g"], unit="m/s^2")
