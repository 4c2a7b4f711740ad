"""The gyro's noise model between the rests: the bias's wander from the rests, the variance
components from the motion residuals, the g-sensitivity test with the wander, and the
coverage of the 95 % intervals in a Monte Carlo with a wandering bias."""

from types import SimpleNamespace

import numpy as np

from accelcal.gyro import noise


def test_wander_variance_is_the_brownian_bridge_integral():
    # a motion spanning the two rest centres: ∫ bridge has variance q D³/12, i.e. q D/12 per unit bias
    q, D = np.array([1e-7, 2e-7, 0.0]), 4.0
    v = noise.wander_variance(q, np.array([0.0, D]), np.array([0.0]), np.array([D]))
    assert np.allclose(v[0], q * D / 12, rtol=1e-2)  # Gauss-Legendre across the kernel's kink: 0.3 %
    # a constant bias from the first rest: the walk's own variance ∫∫ min(t, s) over [2, 4]
    first = lambda tt: np.broadcast_to([1.0, 0.0], (len(tt), 2))  # noqa: E731
    v = noise.wander_variance(q, np.array([0.0, 10.0]), np.array([2.0]), np.array([4.0]), first)
    a, b = 2.0, 4.0
    exact = ((b - a) ** 2 * a + (b - a) ** 3 / 3) / (b - a) ** 2  # ∫∫ min(t, s) over [a, b]², per T²
    assert np.allclose(v[0], q * exact, rtol=1e-2)


def test_wander_variance_matches_simulated_walks_with_rest_means():
    # rests [0, 1] and [3, 4] s, a motion [1, 3] s; the bias is interpolated between the rest means
    rng = np.random.default_rng(2)
    h, n = 0.01, 401
    t = np.arange(n) * h
    walk = np.cumsum(np.sqrt(h) * rng.standard_normal((4000, n)), axis=1)  # q = 1
    ra, rb = walk[:, :101].mean(axis=1), walk[:, 300:].mean(axis=1)
    tm = np.array([0.5, 3.5])
    alpha = (t[100:301] - tm[0]) / (tm[1] - tm[0])
    e = walk[:, 100:301] - (ra[:, None] * (1 - alpha) + rb[:, None] * alpha)
    integral = (e[:, :-1] + e[:, 1:]).sum(axis=1) * h / 2
    pred = noise.wander_variance(np.ones(3), tm, np.array([1.0]), np.array([3.0]),
                                 rest_windows=np.array([[0.0, 1.0], [3.0, 4.0]]))[0, 0] * 4.0
    assert abs(np.var(integral) / pred - 1) < 0.1  # 4000 draws: the variance to 2.2 %
    points = noise.wander_variance(np.ones(3), tm, np.array([1.0]), np.array([3.0]))[0, 0] * 4.0
    assert points > 1.2 * pred  # anchoring at the centres' values would overstate it (can fail)


def _rests(rng, q, p=40, se=2e-5, G=None):
    t = np.sort(rng.uniform(0, 200, p))
    walk = np.cumsum(np.sqrt(q * np.diff(t, prepend=0.0))[:, None] * rng.standard_normal((p, 3)), axis=0)
    f = 9.81 * noise_directions(rng, p)
    means = walk + se * rng.standard_normal((p, 3)) + (0 if G is None else f @ G.T)
    return t, means, np.full((p, 3), se), f


def noise_directions(rng, p):
    u = rng.standard_normal((p, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def test_bias_wander_recovers_the_planted_walk_and_zero_without_one():
    rng = np.random.default_rng(3)
    t, means, se, _ = _rests(rng, 1e-7)
    q = noise.bias_wander(means, se, t)
    assert np.all((q > 0.3e-7) & (q < 3e-7)), q
    t, means, se, _ = _rests(rng, 0.0)
    assert np.all(noise.bias_wander(means, se, t) < 1e-10)


def test_g_sensitivity_test_keeps_its_level_under_a_wandering_bias_and_finds_a_planted_g():
    rng = np.random.default_rng(5)
    p_none = [noise.g_sensitivity_test(m, se, t, f)["p_value"] for t, m, se, f in (_rests(rng, 1e-7) for _ in range(30))]
    assert np.mean(np.array(p_none) < 0.05) <= 0.2  # level 5 %: at most 6 of 30 (binomial, p = 0.01)
    G = np.array([[2e-4, 0, 0], [0, -2e-4, 1e-4], [0, 0, 2e-4]])
    t, means, se, f = _rests(rng, 1e-7, G=G)
    assert noise.g_sensitivity_test(means, se, t, f)["p_value"] < 1e-3


def test_reml_recovers_a_planted_component():
    rng = np.random.default_rng(7)
    n, k = 120, 3
    J = rng.standard_normal((n, 9))
    V = [np.diag(rng.uniform(0.5, 2.0, n)), np.diag(np.repeat(rng.uniform(0, 1, n // 2), 2)), np.eye(n) * 0.3]
    theta = np.array([4.0, 0.0, 1.0])
    est = []
    for _ in range(15):
        S = np.eye(n) + sum(a * v for a, v in zip(theta, V))
        r = np.linalg.cholesky(S) @ rng.standard_normal(n) + J @ rng.standard_normal(9)
        parts = SimpleNamespace(r=r.reshape(-1, 2), J=J.reshape(-1, 2, 9), fixed=np.eye(n), V=tuple(V))
        est.append(noise.estimate_components(parts))
    est = np.array(est)
    assert np.all(est >= 0)
    assert abs(np.mean(est[:, 0] + 0.3 * est[:, 2] / 1.25) - (4.0 + 0.3 / 1.25)) < 1.5  # the total is found
    assert np.median(est[:, 1]) < 0.5  # the absent one stays near zero


def test_accelerometer_direction_covariance_matches_refits():
    # the rests' directions under the accelerometer calibration refitted to re-noised pose means
    import dataclasses

    from accelcal.calibration.fitting import calibrate_poses
    from accelcal.gyro.calibrate import accel_direction_cov
    from accelcal.gyro.simulate import simulate_recording
    from accelcal.static import static_poses_from_intervals

    rng = np.random.default_rng(8)
    M = np.tril(np.eye(3) + rng.normal(0, 5e-3, (3, 3)))
    sim = simulate_recording(rng, n_motions=16, rest_s=1.5, init_rest_s=5.0, acc_noise=0.05, M=M)
    poses = static_poses_from_intervals(sim["t"], sim["acc"], sim["rest_intervals"])
    cal = calibrate_poses(poses, sim["g"], "full_lls", unit="m/s^2")
    f = cal.apply(poses.means)
    sig2 = float(np.sum((np.linalg.norm(f, axis=1) - sim["g"]) ** 2)) / (len(f) - 9)
    pred = accel_direction_cov(cal, f) / sig2  # per unit noise variance of the pose means
    assert pred.shape == (3 * len(f),) * 2 and np.allclose(pred, pred.T)
    assert accel_direction_cov(SimpleNamespace(apply=lambda z: z), f) is None  # no base model: none
    s = 0.01
    us = []
    for _ in range(200):
        noisy = dataclasses.replace(poses, means=poses.means + s * rng.standard_normal(poses.means.shape))
        x = calibrate_poses(noisy, sim["g"], "full_lls", unit="m/s^2").apply(poses.means)
        us.append((x / np.linalg.norm(x, axis=1, keepdims=True)).ravel())
    emp = np.cov(np.array(us).T) / s ** 2
    ratio = np.trace(emp) / np.trace(pred)  # 1.01 on this draw
    assert abs(ratio - 1) < 0.25, ratio
