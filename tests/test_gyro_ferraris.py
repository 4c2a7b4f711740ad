"""Rotations of known angle (the Ferraris protocol): exact recovery, imucal's own numbers, refusals."""

import numpy as np
import pytest

from accelcal.gyro.errors import RotationAngleError
from accelcal.gyro.ferraris import calibrate_ferraris_session, fit_ferraris
from accelcal.gyro.simulate import Motion, random_gyro_matrix


def _turns(C, angles_deg, axes, fs=100.0, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    segs = []
    for ang, ax in zip(angles_deg, axes):
        th = np.deg2rad(ang)
        mo = Motion(np.asarray(ax, float)[None], np.array([th]), np.array([1.875 * abs(th) / np.deg2rad(120)]),
                    np.zeros(1))
        w = mo.rates(np.arange(int(mo.duration * fs) + 20) / fs)
        segs.append(w @ np.linalg.inv(C).T + noise * rng.standard_normal(w.shape))
    return segs


def test_full_turns_about_tilted_axes_give_the_truth():
    rng = np.random.default_rng(1)
    C = random_gyro_matrix(rng, 0.02, 1.0, nominal=np.pi / 180)  # raw deg/s
    axes = np.eye(3) + 0.05 * rng.standard_normal((3, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    segs = _turns(C, [-360, 361.3, 367.2], axes)
    f = fit_ferraris(segs, 0.01, [360, 361.3, 367.2], axes, nominal=np.pi / 180)
    np.testing.assert_allclose(f.C, C, rtol=1e-6, atol=1e-9)
    np.testing.assert_array_equal(f.senses, [-1, 1, 1])


def test_standard_errors_match_the_scatter():
    C = np.eye(3) * np.pi / 180
    errs = []
    for seed in range(60):
        segs = _turns(C, [360, 360, 360], np.eye(3), noise=0.3, seed=seed)
        f = fit_ferraris(segs, 0.01, [360, 360, 360], nominal=np.pi / 180, y_var=np.full(3, 0.09))
        errs.append((f.C - C).reshape(9))
    ratio = np.std(errs, axis=0) / np.sqrt(np.diag(f.cov))
    assert 0.75 < np.median(ratio) < 1.3


def test_a_rotation_short_of_its_stated_angle_is_refused():
    segs = _turns(np.eye(3) * np.pi / 180, [360, 180, 360], np.eye(3))
    with pytest.raises(RotationAngleError, match="the y rotation turns 180.0 deg .* not the stated 360.0"):
        fit_ferraris(segs, 0.01, [360, 360, 360], nominal=np.pi / 180)


def test_a_section_list_without_rotations_is_refused():
    with pytest.raises(RotationAngleError, match="lacks x_a, .*x_rot"):
        calibrate_ferraris_session(np.arange(100) / 100.0, np.zeros((100, 3)), {"x_p": (0, 10)})
