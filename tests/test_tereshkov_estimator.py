"""Tereshkov estimator: the closed forms (11), (12), (14) against each other and against
the simulated AHRS in noise-free settings, and bias recovery."""

import numpy as np
import pytest

from accelcal.errors import AccelcalError, InputShapeError, NonFiniteError
from accelcal.tereshkov import (InvalidParameterError, TereshkovParams, accel_bias_from_torque, run_estimator,
                                steady_state_torque)
from accelcal_repro.tereshkov.vehicle import SensorSpec, VehicleBatch, field_path, sensor_chunks, stack_paths
from accelcal.tereshkov.estimator import concat_results
from accelcal_repro.tereshkov.vehicle import DEG

NOISE_FREE = SensorSpec(imu_rate=25.0, gnss_rate=5.0, gyro_noise=0.0, accel_noise=0.0, gnss_sigma_h=0.0,
                        gnss_sigma_v=0.0)
BG = np.array([0.1, -0.08, 0.0]) * DEG
BA = np.array([0.2, -0.15, 0.1])


def _path(events: dict, duration: float):
    return stack_paths([events], duration, np.random.default_rng(0), terrain_amp_deg=(0.0, 0.0))


def _run(path, params, bg=BG, ba=BA, sensors=NOISE_FREE, record_every_s=1.0):
    R = path.n_runs
    batch = VehicleBatch(path, sensors, np.repeat(np.eye(3)[None], R, 0), np.tile(bg, (R, 1)), np.tile(ba, (R, 1)),
                         np.arange(R))
    dt = 1 / sensors.imu_rate
    parts, state = [], None
    for ch in sensor_chunks(batch, 20.0):
        res, state = run_estimator(ch.gyro, ch.accel, ch.f_ext, ch.course, ch.speed, dt, params, state,
                                   int(round(record_every_s / dt)))
        parts.append(res)
    return concat_results(parts)


FROZEN = TereshkovParams(update_gyro=False, update_accel=False)


@pytest.mark.parametrize("wz_dps", [-12.0, -3.0, 2.0, 6.0, 20.0])
def test_eq14_inverts_eq13(wz_dps):
    """(14) is the exact inverse of the steady-state torque (11) with b_g = 0 and a yaw rate only."""
    rng = np.random.default_rng(1)
    ba = rng.normal(0, 0.2, 3)
    w = np.array([0.0, 0.0, wz_dps * DEG])
    u = steady_state_torque(np.zeros(3), ba, w)
    np.testing.assert_allclose(accel_bias_from_torque(u, w[2])[:2], ba[:2], rtol=1e-12, atol=1e-14)


def test_eq12_is_eq11_without_rotation():
    u = steady_state_torque(BG, BA, np.zeros(3))
    np.testing.assert_allclose(u, BG, atol=1e-15)


def test_straight_torque_balances_gyro_bias_only():
    """Simulated straight motion: the settled torque equals b_g (12), whatever b_a."""
    ev = {"psi0": 0.3, "v0": 3.0, "yaw_t": np.zeros(0), "yaw_dr": np.zeros(0), "speed_t": np.zeros(0),
          "speed_dv": np.zeros(0)}
    bg = np.array([0.1, -0.08, 0.05]) * DEG
    res = _run(_path(ev, 80.0), FROZEN, bg=bg)
    u = res.u[0, res.t >= 50].mean(axis=0)
    np.testing.assert_allclose(u, bg, atol=0.01 * np.abs(bg).max())
    res2 = _run(_path(ev, 80.0), FROZEN, bg=bg, ba=-BA)
    np.testing.assert_allclose(res2.u[0, res2.t >= 50].mean(axis=0), u, atol=1e-3 * np.abs(bg).max())


@pytest.mark.parametrize("rate_dps", [4.0, 10.0])
def test_turning_torque_matches_eq11(rate_dps):
    """Simulated steady turn (no terrain, no z gyro bias): the settled torque is eq. (11)."""
    w = rate_dps * DEG
    ev = {"psi0": 0.0, "v0": 2.0, "yaw_t": np.array([5.0]), "yaw_dr": np.array([w]), "speed_t": np.zeros(0),
          "speed_dv": np.zeros(0)}
    res = _run(_path(ev, 80.0), FROZEN)
    u = res.u[0, res.t >= 50, :2].mean(axis=0)
    pred = steady_state_torque(BG, BA, np.array([0.0, 0.0, w]))[:2]
    np.testing.assert_allclose(u, pred, rtol=0.02, atol=2e-3 * np.abs(pred).max())
    # and the torque really depends on b_a here (unlike straight motion)
    assert np.linalg.norm(pred - steady_state_torque(BG, np.zeros(3), np.array([0.0, 0.0, w]))[:2]) > 0.3 * np.abs(BG).max()


def test_estimator_recovers_injected_biases_noise_free():
    rng = np.random.default_rng(3)
    ev = field_path(rng, 700.0, straight_s=(20, 30), turn_deg=(360, 360), turn_rate_dps=(8, 10))
    res = _run(_path(ev, 700.0), TereshkovParams(), bg=np.array([0.12, -0.09, 0.07]) * DEG)
    gb, ab = res.gyro_bias[0, -1], res.accel_bias[0, -1]
    np.testing.assert_allclose(gb[:2], np.array([0.12, -0.09]) * DEG, atol=0.02 * 0.1 * DEG)
    np.testing.assert_allclose(ab[:2], BA[:2], atol=0.005)
    # the estimates start at zero and move towards the truth monotonically on average
    err = np.abs(res.accel_bias[0, :, :2] - BA[:2]).sum(-1)
    assert err[len(err) // 2] < 0.5 * err[0]


@pytest.mark.parametrize("variant", [{"accel_feedback": False}, {"accel_formula": "eq13"}])
def test_variants_same_limit(variant):
    """No accelerometer feedback (low-pass of (14) itself), or the general (13): same limit."""
    rng = np.random.default_rng(3)
    ev = field_path(rng, 400.0, straight_s=(20, 30), turn_deg=(360, 360), turn_rate_dps=(8, 10))
    res = _run(_path(ev, 400.0), TereshkovParams(**variant), sensors=SensorSpec(
        imu_rate=10.0, gnss_rate=5.0, gyro_noise=0.0, accel_noise=0.0, gnss_sigma_h=0.0, gnss_sigma_v=0.0))
    np.testing.assert_allclose(res.accel_bias[0, -1, :2], BA[:2], atol=0.01)


def test_bad_inputs_raise_typed_errors():
    R, n = 2, 10
    z = np.zeros((R, n, 3))
    c = np.zeros((R, n))
    with pytest.raises(InputShapeError):
        run_estimator(np.zeros((R, n, 2)), z, z, c, c, 0.02)
    with pytest.raises(InputShapeError):
        run_estimator(z, z, z, np.zeros((R, n + 1)), c, 0.02)
    bad = z.copy()
    bad[0, 3, 1] = np.nan
    with pytest.raises(NonFiniteError):
        run_estimator(z, bad, z, c, c, 0.02)
    with pytest.raises(InvalidParameterError):
        run_estimator(z, z, z, c, c, -0.02)
    with pytest.raises(InvalidParameterError):
        TereshkovParams(tau=0.0)
    with pytest.raises(InvalidParameterError):
        TereshkovParams(straight_rate_dps=5.0, turn_rate_dps=3.0)
    with pytest.raises(InvalidParameterError):
        TereshkovParams(accel_formula="eq15")
    with pytest.raises(InvalidParameterError):
        accel_bias_from_torque(np.ones(3), 0.0)
    assert issubclass(InvalidParameterError, AccelcalError)


def test_scalar_and_vectorised_implementations_agree():
    """Two independent implementations (numpy over runs; plain Python floats) of the same
    estimator give the same numbers on noisy data."""
    from accelcal.tereshkov.estimator import run_estimator_scalar

    rng = np.random.default_rng(8)
    ev = field_path(rng, 200.0, straight_s=(20, 30), turn_deg=(360, 360), turn_rate_dps=(8, 10))
    p = _path(ev, 200.0)
    batch = VehicleBatch(p, SensorSpec(imu_rate=20.0), np.eye(3)[None], BG[None], BA[None], np.array([4]))
    ch = next(sensor_chunks(batch, 200.0))
    params = TereshkovParams(turn_settle_s=4.0, straight_settle_s=6.0)
    vec, _ = run_estimator(ch.gyro, ch.accel, ch.f_ext, ch.course, ch.speed, 0.05, params, record_every=20)
    one = run_estimator_scalar(ch.gyro[0], ch.accel[0], ch.f_ext[0], ch.course[0], ch.speed[0], 0.05, params,
                               record_every=20)
    assert vec.accel_time[0, -1] > 20 and vec.gyro_time[0, -1] > 20  # both estimators were exercised
    for name in ("gyro_bias", "accel_bias", "u", "C", "mode_time"):
        np.testing.assert_allclose(getattr(one, name), getattr(vec, name), rtol=1e-9, atol=1e-12, err_msg=name)
