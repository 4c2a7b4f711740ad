"""Tereshkov vehicle simulation: exact kinematics, streaming and per-run independence,
and the installation-angle behaviour of the estimator on it."""

import numpy as np
import pytest

from accelcal.errors import InputShapeError
from accelcal.tereshkov import InvalidParameterError, TereshkovParams, run_estimator
from accelcal.tereshkov.estimator import concat_results
from accelcal_repro.tereshkov.montecarlo import equivalent_accel_bias
from accelcal_repro.tereshkov.vehicle import (DEG, G, SensorSpec, VehicleBatch, field_path, installation_dcm,
                                              sensor_chunks, stack_paths, straight_path, vehicle_state)


@pytest.fixture(scope="module")
def path():
    rng = np.random.default_rng(5)
    runs = [field_path(rng, 300.0), straight_path(rng, 300.0)]
    return stack_paths(runs, 300.0, rng, lean_deg_per_mps2=1.5)


def test_kinematics_are_consistent(path):
    t = np.linspace(100.0, 140.0, 40001)
    st = vehicle_state(path, t)
    dt = t[1] - t[0]
    np.testing.assert_allclose(np.gradient(st.v_n, dt, axis=1)[:, 2:-2], st.a_n[:, 2:-2], atol=2e-4)
    np.testing.assert_allclose(np.gradient(st.heading, dt, axis=1)[:, 2:-2], st.yaw_rate[:, 2:-2], atol=1e-6)
    dC = np.gradient(st.C_nb, dt, axis=1)
    Om = np.swapaxes(st.C_nb, -1, -2) @ dC  # skew(ω_b)
    w = np.stack([Om[..., 2, 1], Om[..., 0, 2], Om[..., 1, 0]], -1)
    np.testing.assert_allclose(w[:, 2:-2], st.omega_b[:, 2:-2], atol=1e-6)
    # at constant speed on a straight, level stretch the specific force is -g along the body z
    f_n = np.einsum("rnij,rnj->rni", st.C_nb, st.f_b)
    np.testing.assert_allclose(f_n[..., 2], st.a_n[..., 2] - G, atol=1e-12)
    # small roll and pitch, tractor speeds
    assert np.abs(st.roll).max() < 5 * DEG and np.abs(st.pitch).max() < 5 * DEG
    assert 1.0 < st.speed.min() and st.speed.max() < 5.0


def _batch(path, seeds, sensors=None):
    R = path.n_runs
    return VehicleBatch(path, sensors or SensorSpec(imu_rate=20.0), np.repeat(np.eye(3)[None], R, 0),
                        np.full((R, 3), 0.1 * DEG), np.full((R, 3), 0.2), np.asarray(seeds))


def test_chunking_and_batching_do_not_change_the_data(path):
    a = list(sensor_chunks(_batch(path, [1, 2]), 7.0))
    b = list(sensor_chunks(_batch(path, [1, 2]), 30.0))
    cat = lambda chunks, k: np.concatenate([getattr(c, k) for c in chunks], axis=1)
    for k in ("gyro", "accel", "f_ext", "course", "speed"):
        np.testing.assert_allclose(cat(a, k), cat(b, k), rtol=1e-12, atol=1e-12)  # same up to rounding
    # run 0 alone sees the same data as in the batch
    single = list(sensor_chunks(_batch(path.take([0]), [1]), 30.0))
    np.testing.assert_allclose(cat(single, "gyro")[0], cat(b, "gyro")[0], rtol=1e-12, atol=1e-12)
    # a different seed, different noise
    other = list(sensor_chunks(_batch(path, [3, 2]), 30.0))
    assert not np.allclose(cat(other, "gyro")[0], cat(b, "gyro")[0])


def test_external_force_from_gnss_matches_truth(path):
    quiet = SensorSpec(imu_rate=20.0, gyro_noise=0, accel_noise=0, gnss_sigma_h=0, gnss_sigma_v=0)
    chunks = list(sensor_chunks(_batch(path, [1, 2], quiet), 30.0))
    f_ext = np.concatenate([c.f_ext for c in chunks], axis=1)
    t = np.concatenate([c.t for c in chunks]) + 1 / 40.0
    st = vehicle_state(path, t)
    f_true = st.a_n - np.array([0, 0, G])
    # differentiated 10 Hz velocity: errors only where the acceleration changes fast
    assert np.sqrt(np.mean((f_ext - f_true) ** 2)) < 5e-3


def test_bad_batches_raise():
    rng = np.random.default_rng(0)
    p = stack_paths([straight_path(rng, 10.0)], 10.0, rng)
    with pytest.raises(InputShapeError):
        VehicleBatch(p, SensorSpec(), np.eye(3), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros(1))
    with pytest.raises(InvalidParameterError):
        SensorSpec(imu_rate=5.0, gnss_rate=10.0)
    with pytest.raises(InvalidParameterError):
        stack_paths([straight_path(rng, 10.0)], -1.0, rng)
    with pytest.raises(InvalidParameterError):
        field_path(rng, 100.0, turn_direction="sideways")


def test_tilted_installation_gives_equivalent_biases():
    """15° roll and pitch mounting, noise free: the accelerometer estimates converge to the
    equivalent x/y biases (the unestimated z bias leaks in as b_z·tan(tilt)), not to the
    sensor-axis biases; the gyro estimates are unaffected."""
    rng = np.random.default_rng(3)
    ev = field_path(rng, 600.0, straight_s=(20, 30), turn_deg=(360, 360), turn_rate_dps=(8, 10))
    p = stack_paths([ev], 600.0, rng, terrain_amp_deg=(0.0, 0.0))
    C_bs = installation_dcm(15.0, 15.0, 0.0)[None]
    bg = np.array([[0.1, -0.08, 0.05]]) * DEG
    ba = np.array([[0.2, -0.15, 0.25]])
    quiet = SensorSpec(imu_rate=20.0, gyro_noise=0, accel_noise=0, gnss_sigma_h=0, gnss_sigma_v=0)
    batch = VehicleBatch(p, quiet, C_bs, bg, ba, np.array([0]))
    parts, state = [], None
    for ch in sensor_chunks(batch, 30.0):
        r, state = run_estimator(ch.gyro, ch.accel, ch.f_ext, ch.course, ch.speed, 0.05, TereshkovParams(), state)
        parts.append(r)
    res = concat_results(parts)
    eq = equivalent_accel_bias(ba, C_bs)[0]
    np.testing.assert_allclose(res.accel_bias[0, -1, :2], eq, atol=0.006)
    assert np.abs(eq - ba[0, :2]).max() > 0.05  # the leak is real at 15°
    np.testing.assert_allclose(res.gyro_bias[0, -1, :2], bg[0, :2], atol=0.005 * DEG)
