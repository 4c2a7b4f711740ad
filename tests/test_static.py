"""Static-interval detection: simulated sessions with known poses, the three real recordings, failures."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.signal import lfilter

from accelcal.errors import AccelcalError, RecordingError
from accelcal.formats.imucal import read_imucal_session
from accelcal.formats.imucal_annotated import read_imucal_annotated
from accelcal.formats.imutk import read_imutk_ascii
from accelcal.formats.intervals import read_imucal_section_list
from accelcal.formats.mpu6050 import read_mpu6050_csv
from accelcal.nominal import nominal_conversion
from accelcal.static import detect_static, detect_static_recording

G = 9.81


@pytest.fixture(scope="module")
def data_dir() -> Path:
    d = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
    if not d.is_dir():
        pytest.skip("shared/data not available")
    return d


# --------------------------------------------------------------------------- simulation


def _great_circle(u0, u1, n):
    """Rotation from u0 to u1 along the great circle, smooth (cosine) speed profile."""
    s = 0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, n))
    ang = np.arccos(np.clip(u0 @ u1, -1.0, 1.0))
    if ang < 1e-9:
        return np.repeat(u0[None], n, axis=0)
    return (np.sin((1 - s) * ang)[:, None] * u0 + np.sin(s * ang)[:, None] * u1) / np.sin(ang)


def simulate(rng, dirs, *, sigma=0.01, fs=100.0, init_rest=20.0, rest=(3.0, 6.0), move=(1.5, 3.0),
             shake=5.0, noise=None):
    """Rests at ``G * dirs`` joined by smooth rotations with extra shake (``shake * sigma``).

    Returns t, acc and the true pose accelerations.  ``noise`` (n, 3) replaces the white
    noise if given (for correlated-noise tests).
    """
    chunks = []
    for i, u in enumerate(dirs):
        n_rest = int((init_rest if i == 0 else rng.uniform(*rest)) * fs)
        chunks.append(np.repeat(G * u[None], n_rest, axis=0))
        if i + 1 < len(dirs):
            m = int(rng.uniform(*move) * fs)
            path = G * _great_circle(u, dirs[i + 1], m)
            path += shake * sigma * np.sin(np.linspace(0, np.pi, m))[:, None] * rng.standard_normal((m, 3))
            chunks.append(path)
    x = np.concatenate(chunks)
    e = sigma * rng.standard_normal(x.shape) if noise is None else noise(x.shape)
    return np.arange(len(x)) / fs, x + e, G * np.asarray(dirs)


def random_dirs(rng, n):
    d = rng.standard_normal((n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.mark.parametrize("seed", range(5))
def test_simulated_poses_found_exactly(seed):
    rng = np.random.default_rng(seed)
    dirs = random_dirs(rng, 15)
    t, acc, truth = simulate(rng, dirs)
    p = detect_static(t, acc)
    assert len(p) == len(dirs)
    z = (p.means - truth) / p.mean_std
    assert np.abs(z).max() < 5.0  # means unbiased to within the reported standard error
    assert np.all(np.diff(p.intervals[:, 0]) > 0) and np.all(p.intervals[:, 1] > p.intervals[:, 0])
    assert p.intervals[0, 0] == 0 and p.init_rest[0] == 0  # initial rest is the first pose
    np.testing.assert_allclose(p.noise_std, 0.01, rtol=0.25)
    np.testing.assert_array_equal(p.n_samples, p.intervals[:, 1] - p.intervals[:, 0])
    np.testing.assert_allclose(p.t_mid, 0.5 * (p.t_start + p.t_end))


def test_simulated_raw_counts_like_xsens():
    """Quantised counts around 32768 (Xsens-like): same poses; no precision lost in the sums."""
    rng = np.random.default_rng(11)
    dirs = random_dirs(rng, 12)
    t, acc, truth = simulate(rng, dirs, sigma=0.008, init_rest=50.0)
    counts = np.round(32768 + 415 * acc)
    p = detect_static(t, counts)
    assert len(p) == len(dirs)
    assert np.abs(p.means - (32768 + 415 * truth)).max() < 1.0  # counts; noise std ≈ 3.3 counts


def test_explicit_init_duration_matches_automatic():
    rng = np.random.default_rng(3)
    t, acc, _ = simulate(rng, random_dirs(rng, 10))
    a, b = detect_static(t, acc), detect_static(t, acc, init_duration=15.0)
    assert len(a) == len(b) == 10
    assert b.init_rest == (0, 1500)
    np.testing.assert_allclose(a.means, b.means, atol=2e-3)


def test_mean_std_white_noise_is_sigma_over_sqrt_n():
    rng = np.random.default_rng(5)
    t, acc, _ = simulate(rng, random_dirs(rng, 12))
    p = detect_static(t, acc)
    ratio = p.mean_std / (0.01 / np.sqrt(p.n_samples[:, None]))
    assert 0.9 < np.median(ratio) < 1.3  # τ ≈ 1 for white noise (clamped at 1, slightly conservative)


def test_mean_std_accounts_for_correlated_noise():
    """AR(1) noise, φ = 0.8: τ = (1 + φ)/(1 - φ) = 9, so the standard error is 3× σ/√n.

    The pose errors divided by the reported ``mean_std`` must then have unit spread:
    ignoring the correlation would give a spread of 3.
    """
    phi, sigma = 0.8, 0.01
    z = []
    for seed in range(6):
        rng = np.random.default_rng(100 + seed)
        dirs = random_dirs(rng, 12)

        def ar1(shape):
            e = rng.standard_normal(shape) * sigma * np.sqrt(1 - phi ** 2)  # stationary std = sigma
            return lfilter([1.0], [1.0, -phi], e, axis=0)

        t, acc, truth = simulate(rng, dirs, noise=ar1, rest=(4.0, 8.0))
        p = detect_static(t, acc)
        assert len(p) == len(dirs)
        ratio = p.mean_std / (p.noise_std / np.sqrt(p.n_samples[:, None]))
        assert 2.0 < np.median(ratio) < 4.0
        z.append(((p.means - truth) / p.mean_std)[1:])  # skip the long initial rest: few pose-level samples anyway
    z = np.concatenate(z).ravel()
    assert 0.7 < z.std() < 1.4


def test_temperature_is_averaged_per_pose():
    rng = np.random.default_rng(8)
    t, acc, _ = simulate(rng, random_dirs(rng, 6))
    temp = 20.0 + 0.1 * t
    p = detect_static(t, acc, temp=temp)
    expected = [temp[a:b].mean() for a, b in p.intervals]
    np.testing.assert_allclose(p.temp, expected)
    assert detect_static(t, acc).temp is None


# --------------------------------------------------------------------------- failures


def _one_line(err: pytest.ExceptionInfo) -> str:
    msg = str(err.value)
    assert msg and "\n" not in msg and "Traceback" not in msg
    return msg


def _rotating(fs=100.0, seconds=60.0, deg_per_s=20.0, sigma=0.01, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    a = np.deg2rad(deg_per_s) * t
    x = G * np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])
    return t, x + sigma * rng.standard_normal(x.shape)


@pytest.mark.parametrize("rate", [20.0, 1.0, 0.2])
def test_never_resting_sensor_raises(rate):
    t, acc = _rotating(deg_per_s=rate)
    with pytest.raises(RecordingError) as e:
        detect_static(t, acc)
    assert "not at rest" in _one_line(e)


def test_random_walk_motion_raises():
    rng = np.random.default_rng(1)
    acc = G * np.array([0, 0, 1.0]) + np.cumsum(0.01 * rng.standard_normal((6000, 3)), axis=0)
    with pytest.raises(RecordingError) as e:
        detect_static(np.arange(6000) / 100.0, acc)
    assert "not at rest" in _one_line(e)


def _shaking_at_start():
    rng = np.random.default_rng(2)
    t, acc, truth = simulate(rng, random_dirs(rng, 8))
    acc[:500] += 0.2 * rng.standard_normal((500, 3))  # 5 s of vibration, 20× the noise
    return t, acc, truth


def _rotation_at_start():
    rng = np.random.default_rng(4)
    dirs = random_dirs(rng, 8)
    t, acc, truth = simulate(rng, dirs)
    lead = G * _great_circle(np.array([1.0, 0, 0]), dirs[0], 300) + 0.01 * rng.standard_normal((300, 3))
    return np.arange(300 + len(acc)) / 100.0, np.concatenate([lead, acc]), truth


@pytest.mark.parametrize("make", [_shaking_at_start, _rotation_at_start])
def test_no_initial_rest_raises_when_the_initial_rest_is_required(make):
    t, acc, _ = make()
    with pytest.raises(RecordingError) as e:
        detect_static(t, acc, noise_reference="initial")
    assert "not at rest" in _one_line(e)


@pytest.mark.parametrize("make", [_shaking_at_start, _rotation_at_start])
def test_no_initial_rest_falls_back_to_the_quietest_stretch(make):
    """The default ('auto') takes the noise level from the quietest 2 s, says why, and
    finds the same poses (the first one shortened by the disturbed start)."""
    t, acc, truth = make()
    p = detect_static(t, acc)
    assert p.reference == "quietest_stretch"
    assert "not at rest" in p.reference_note and "quietest 2.0 s stretch" in p.reference_note
    assert len(p) == len(truth)
    z = (p.means - truth) / p.mean_std
    assert np.abs(z).max() < 5.0


def test_quietest_reference_can_be_forced():
    rng = np.random.default_rng(3)
    t, acc, _ = simulate(rng, random_dirs(rng, 10))
    a, b = detect_static(t, acc), detect_static(t, acc, noise_reference="quietest")
    assert a.reference == "initial_rest" and a.reference_note == "" and b.reference == "quietest_stretch"
    assert len(a) == len(b) == 10


def test_bad_noise_reference_raises():
    t, acc, _ = simulate(np.random.default_rng(3), random_dirs(np.random.default_rng(3), 5))
    with pytest.raises(AccelcalError, match="noise_reference"):
        detect_static(t, acc, noise_reference="first")


def test_init_duration_covering_motion_raises():
    rng = np.random.default_rng(6)
    t, acc, _ = simulate(rng, random_dirs(rng, 8))  # initial rest lasts 20 s
    with pytest.raises(RecordingError) as e:
        detect_static(t, acc, init_duration=22.0)
    assert "not at rest" in _one_line(e)


def test_stuck_sensor_raises():
    with pytest.raises(RecordingError) as e:
        detect_static(np.arange(3000) / 100.0, np.ones((3000, 3)))
    assert "constant" in _one_line(e)


def test_bad_arrays_raise():
    rng = np.random.default_rng(7)
    t, acc, _ = simulate(rng, random_dirs(rng, 4))
    bad = acc.copy()
    bad[100, 1] = np.nan
    with pytest.raises(RecordingError) as e:
        detect_static(t, bad)
    assert "non-finite" in _one_line(e)
    bad = acc.copy()
    bad[5, 0] = np.inf
    with pytest.raises(RecordingError):
        detect_static(t, bad)
    with pytest.raises(RecordingError) as e:
        detect_static(t[::-1], acc)
    assert "strictly increasing" in _one_line(e)
    with pytest.raises(RecordingError) as e:
        detect_static(t[:250], acc[:250])
    assert "too short" in _one_line(e)
    with pytest.raises(RecordingError):
        detect_static(t, acc[:, :2])


# --------------------------------------------------------------------------- real recordings


def _timed(rec, **kw):
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        p = detect_static_recording(rec, **kw)
        best = min(best, time.perf_counter() - t0)
    return p, best


def _full_model_residuals(means, offset, counts_per_unit, g):
    """Fit z = L x + b, |x| = g (L lower triangular: scale, misalignment); relative norm residuals."""
    def res(q):
        L = np.array([[q[3], 0, 0], [q[4], q[5], 0], [q[6], q[7], q[8]]])
        return np.linalg.norm(np.linalg.solve(L, (means - q[:3]).T), axis=0) / g - 1.0
    q0 = np.r_[offset, counts_per_unit[0], 0, counts_per_unit[1], 0, 0, counts_per_unit[2]]
    sol = least_squares(res, q0)
    return res(sol.x), sol.x


def test_xsens_poses(data_dir):
    rec = read_imutk_ascii(data_dir / "imu_tk_xsens" / "xsens_acc.mat")
    p, seconds = _timed(rec)
    print(f"xsens: {len(p)} poses in {seconds * 1e3:.0f} ms, initial rest {p.init_rest[1] / rec.rate:.1f} s")
    assert seconds < 1.0
    assert len(p) >= 30
    assert len(p) == 38  # regression: initial rest + 37 hand-placed orientations
    assert 50.0 < p.t_end[0] < 53.0  # README: initial rest of about 50 s
    conv = nominal_conversion("imutk_xsens")
    # Nominal scale, nominal bias 32768: every pose has a plausible gravity norm.  Not
    # "nearly constant": the true biases are 350-500 counts (≈1 m/s²) off 32768.
    norms = np.linalg.norm(conv.to_si(p.means), axis=1)
    assert np.all((norms > 0.8 * conv.g_local) & (norms < 1.2 * conv.g_local))
    # With bias, scale and misalignment fitted, all 38 poses lie on one ellipsoid to
    # 0.1 % of g (≈ 4 counts): a pose that averaged over any motion would stand out.
    r, q = _full_model_residuals(p.means, conv.offset, conv.counts_per_unit, conv.g_local)
    assert np.abs(r).max() < 1e-3
    np.testing.assert_allclose(q[[3, 5, 8]], conv.counts_per_unit, rtol=0.01)
    # The noise the estimators will use: Xsens per-sample std ≈ 3.3 counts.
    assert np.all((np.median(p.noise_std, axis=0) > 2.5) & (np.median(p.noise_std, axis=0) < 4.5))


def test_xsens_explicit_init_duration(data_dir):
    rec = read_imutk_ascii(data_dir / "imu_tk_xsens" / "xsens_acc.mat")
    a, b = detect_static_recording(rec), detect_static_recording(rec, init_duration=50.0)
    assert len(a) == len(b)
    np.testing.assert_allclose(a.means[1:], b.means[1:], atol=0.5)  # counts


def test_mpu6050_poses(data_dir):
    rec = read_mpu6050_csv(data_dir / "mpu6050_suarez" / "example_data_calibration.csv")
    p, seconds = _timed(rec)
    print(f"mpu6050: {len(p)} poses in {seconds * 1e3:.0f} ms, initial rest {p.init_rest[1] / rec.rate:.1f} s")
    assert seconds < 1.0
    assert len(p) == 10  # initial rest + 9 hand-placed poses
    assert 36.0 < p.t_end[0] < 38.0  # header: initialization time 36.5 s
    assert np.all(p.t_end[1:] - p.t_start[1:] > 1.0)
    conv = nominal_conversion("mpu6050")
    norms = np.linalg.norm(conv.to_si(p.means), axis=1)
    assert np.all((norms > 0.8 * G) & (norms < 1.2 * G))
    assert len(detect_static_recording(rec, init_duration=36.5)) == 10


def test_imucal_session_matches_section_list(data_dir):
    d = data_dir / "imucal_ferraris"
    rec = read_imucal_session(d / "example_ferraris_session.csv")
    sections = read_imucal_section_list(d / "example_ferraris_session_list.json")
    p, seconds = _timed(rec)
    print(f"imucal session: {len(p)} poses in {seconds * 1e3:.0f} ms, initial rest {p.init_rest[1] / rec.rate:.2f} s")
    assert seconds < 1.0
    iv = p.intervals
    for name in ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a"):
        s, e = sections[name]
        overlap = np.minimum(iv[:, 1], e) - np.maximum(iv[:, 0], s)
        j = int(np.argmax(overlap))
        assert overlap[j] >= 0.95 * (e - s), name  # the labelled static range lies in one detected pose
        assert np.abs(p.means[j] - rec.acc[s:e].mean(axis=0)).max() < 5e-3, name  # m/s²
    for name in ("x_rot", "y_rot", "z_rot"):
        s, e = sections[name]
        overlap = np.minimum(iv[:, 1], e) - np.maximum(iv[:, 0], s)
        # nothing static detected inside a rotation, up to the hand-set bounds of the section list
        # (at imucal's 102.4 Hz a rest reaches 4 samples, 40 ms, into y_rot)
        assert overlap.max() <= 0.05 * rec.rate, name
    assert len(p) == 13  # regression: the six positions, repeated x/y/z rests around the rotations, initial rest


def test_imucal_annotated_static_parts(data_dir):
    rec, parts = read_imucal_annotated(data_dir / "imucal_ferraris" / "annotated_session.csv")
    p = detect_static_recording(rec)
    for (a, b), name in zip(p.intervals, ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")):
        assert set(parts[a:b]) == {name}
        assert b - a > 0.5 * np.count_nonzero(parts == name)
    # at imucal's 102.4 Hz the detection also finds the pauses of 1.4-2.3 s inside the *_rot parts
    # (the part labels cover the whole turn): the gyro is at rest there, not turning
    turning = np.linalg.norm(rec.gyro[np.char.endswith(parts.astype(str), "_rot")], axis=1).mean()
    assert len(p) == 9
    for a, b in p.intervals[6:]:
        assert str(parts[a]).endswith("_rot") and np.linalg.norm(rec.gyro[a:b], axis=1).mean() < 0.05 * turning
