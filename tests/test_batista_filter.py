"""Batista et al. (2011), Sec. IV: kinematics, discretisation, the Kalman filter, observability."""

import numpy as np
import pytest
from scipy.linalg import expm

from accelcal import InputShapeError, NonFiniteError
from accelcal.batista.filter import (PAPER_XI, covariance_sequence, discretize_van_loan, kalman_filter,
                                     observability_gramian, process_noise, rotation_blocks, system_matrix, transition)
from accelcal.batista.model import PAPER_FILTER_BIAS, skew
from accelcal_repro.batista2011.montecarlo import (filter_montecarlo, filter_scenario, gramian_table, initial_estimate,
                                                   observability_table, shared_gain_filter)
from accelcal_repro.batista2011.montecarlo.filter import _measurements
from accelcal_repro.batista2011.montecarlo.shared_gain import _blocks_bkt
from accelcal_repro.batista2011.claims import steady_mean, steady_state
from accelcal_repro.batista2011.trajectory import constant_axis_attitude, euler_sinusoid_attitude

P0 = np.repeat([0.01**2, 0.2**2, 0.2**2], 3)
AXIS = np.array([1.0, 0.0, 0.0])


def _changing(duration=60.0, rate=100.0):
    t = np.arange(int(duration * rate) + 1) / rate
    return euler_sinusoid_attitude(t, [0, 0, 0], [90, 45, 180], [0.03, 0.02, 0.01], [0, 45, 0], [0, 0, 0])


def _constant(duration=60.0, rate=100.0):
    t = np.arange(int(duration * rate) + 1) / rate
    return constant_axis_attitude(t, AXIS, [0, 30, 0], 10.0, 30.0, 0.02)


def _scenario(att, gyro=0.05):
    return filter_scenario(att, PAPER_FILTER_BIAS, 0.0013, gyro, 0.01, 9.81, [0.05, -0.03, 0.1])


def test_attitude_kinematics_are_consistent():
    att = _changing(10.0, 1000.0)
    dt = 1e-3
    # Ṙ = R S(ω): central differences of R against the analytic ω
    Rdot = (att.R[2:] - att.R[:-2]) / (2 * dt)
    W = np.einsum("nji,njk->nik", att.R[1:-1], Rdot)
    np.testing.assert_allclose(W, skew(att.omega[1:-1]), atol=1e-5)
    np.testing.assert_allclose((att.omega[2:] - att.omega[:-2]) / (2 * dt), att.omega_dot[1:-1], atol=1e-5)
    c = _constant(10.0, 1000.0)
    np.testing.assert_allclose(np.cross(c.omega, AXIS), 0, atol=1e-15)
    # ġ = -S(ω) g for the body-frame gravity of the scenario
    sc = _scenario(att)
    g = sc.signals["g"]
    np.testing.assert_allclose((g[2:] - g[:-2]) / (2 * dt), -np.cross(att.omega[1:-1], g[1:-1]), atol=1e-4)


@pytest.mark.parametrize("w", [[0.3, -0.2, 0.5], [1e-7, 0, 0], [0.0, 0.0, 0.0], [30.0, -20.0, 50.0]])
def test_closed_form_discretisation_equals_van_loan(w):
    dt = 0.01
    Phi, G0, G1 = transition(np.array(w), dt)
    Q = process_noise(np.array(w), dt, PAPER_XI)
    P2, H0, H1, Q2 = discretize_van_loan(np.array(w), dt, np.array(PAPER_XI))
    np.testing.assert_allclose(Phi, expm(system_matrix(np.array(w)) * dt), atol=1e-14)
    np.testing.assert_allclose(Phi, P2, atol=1e-14)
    np.testing.assert_allclose(G0, H0, atol=1e-15)
    np.testing.assert_allclose(G1, H1, atol=1e-15)
    np.testing.assert_allclose(Q, Q2, rtol=1e-6, atol=1e-6 * np.abs(Q2).max())
    E, _, _ = rotation_blocks(np.array(w), dt)
    np.testing.assert_allclose(E @ E.T, np.eye(3), atol=1e-14)


def test_batched_blocks_match_the_reference():
    w = np.random.default_rng(0).normal(0, 2.0, (7, 3, 5))  # (B, 3, T), some with |ω| dt > 0.02
    E, J0, J1 = _blocks_bkt(w, 0.01)
    rE, rJ0, rJ1 = rotation_blocks(np.moveaxis(w, 1, -1), 0.01)  # (B, T, 3, 3)
    for mine, ref in ((E, rE), (J0, rJ0), (J1 * 0.01, rJ1)):
        np.testing.assert_allclose(np.moveaxis(mine, -1, 1), ref, atol=1e-15)


def test_noise_free_filter_stays_on_the_truth_with_second_order_error():
    """Exact initial state, no noise: the error is the discretisation error alone, O(dt²).

    A sign error in A(t), a zero-order hold of a_m (bias ~|ω| g dt / 2 ≈ 0.02 m/s²) or a
    first-order scheme would all fail this."""
    errs = []
    for rate in (100.0, 200.0):
        sc = _scenario(_changing(60.0, rate))
        s = sc.signals
        r = kalman_filter(sc.t, s["a"] + sc.bias, sc.attitude.omega, s["v"], sc.x_true()[0], P0)
        errs.append(np.abs(r.x - sc.x_true()).max())
    assert errs[0] < 1e-4
    assert errs[0] / errs[1] > 3.0  # second order: halving dt divides the error by ~4


def test_shared_gain_batch_matches_the_exact_filter():
    sc = _scenario(_changing(60.0))
    rng = np.random.default_rng(1)
    a, w, y = _measurements(sc, np.arange(len(sc.t)), rng.spawn(3))
    x0 = initial_estimate(a[:, 0], y[:, 0])
    K, _ = covariance_sequence(sc.t, sc.attitude.omega, P0)
    out = shared_gain_filter(sc.dt, a, w, y, x0, K, np.arange(len(sc.t)))
    for i in range(3):
        r = kalman_filter(sc.t, a[i], w[i], y[i], x0[i], P0)
        # gains from the true ω instead of this run's gyro readings: a negligible difference
        # (far below the filter's σ and 20x below the accelerometer noise)
        d = np.abs(out[i] - r.x)
        assert (d / r.sigma).max() < 3e-3 and d.max() < 1e-4
    # Joseph-form covariance stays symmetric positive definite
    _, sig, P = covariance_sequence(sc.t, sc.attitude.omega, P0, return_covariance=True)
    assert np.allclose(P, np.swapaxes(P, 1, 2)) and np.all(np.linalg.eigvalsh(P[-1]) > 0)


@pytest.fixture(scope="module")
def changing_mc():
    sc = _scenario(_changing(150.0))
    return sc, filter_montecarlo(sc, np.random.default_rng(2).spawn(40), P0, record_every_s=1.0, summary_every_s=0.5)


def test_mean_error_converges_to_zero_within_the_filter_sigma(changing_mc):
    sc, mc = changing_mc
    sm = steady_mean(mc.runs, 100.0)
    assert (sm["t_stat"].abs() < 4.0).all(), sm
    s = mc.summary
    first, last = s[s["t"] == 0].set_index("state"), s[s["t"] == s["t"].max()].set_index("state")
    for c in ("b_x", "b_y", "b_z"):
        assert last.loc[c, "rms_error"] < 0.05 * first.loc[c, "rms_error"]
    for c in ("g_x", "g_y"):  # g_z starts near its steady level (ĝ = -a_m); the gyro noise sets the floor
        assert last.loc[c, "rms_error"] < 0.1 * first.loc[c, "rms_error"]
    # every run's error stays within its ±3σ band nearly all the time
    e = mc.runs[[c for c in mc.runs.columns if c.startswith("e_")]].to_numpy().reshape(40, -1, 9)
    sig = np.sqrt(np.einsum("kii->ki", mc.P))
    assert np.mean(np.abs(e) <= 3 * sig[None]) > 0.95
    ss = steady_state(s, 100.0).set_index("state")
    assert (ss["rms_error"] < ss["filter_sigma"]).all()


def test_constant_omega_direction_leaves_the_axial_components_unobserved(changing_mc):
    """Sec. IV: with ω along n, g·n and b·n cannot be told apart; the rest converges."""
    _, mc_change = changing_mc
    sc = _scenario(_constant(150.0))
    mc = filter_montecarlo(sc, np.random.default_rng(3).spawn(30), P0, record_every_s=1.0, summary_every_s=1.0)
    obs = observability_table(mc, AXIS, "constant").set_index(["component", "t"])["rms_error"]
    obs_c = observability_table(mc_change, AXIS, "changing").set_index(["component", "t"])["rms_error"]
    t_end = 150.0
    for comp in ("g_axial", "b_axial"):
        assert obs[(comp, t_end)] > 0.5 * obs[(comp, 0.0)]  # stuck
        assert obs_c[(comp, t_end)] < 0.1 * obs_c[(comp, 0.0)]  # converges when ω turns
    for comp in ("g_perp", "b_perp"):
        assert obs[(comp, t_end)] < 0.1 * obs[(comp, 0.0)]
    # the filter's own σ along the axis does not shrink either
    s_ax = np.sqrt(np.einsum("i,kij,j->k", AXIS, mc.P[:, 6:9, 6:9], AXIS))
    assert s_ax[-1] > 0.5 * s_ax[0]
    # observability Gramian: singular with null vector (0, n, n) only for the fixed axis
    n = int(60 / sc.dt) + 1
    gc = gramian_table(sc.t[:n], sc.attitude.omega[:n], AXIS, "constant").iloc[0]
    assert gc["eig_ratio"] < 1e-12 and gc["null_alignment"] > 0.999
    att = _changing(60.0)
    gv = gramian_table(att.t, att.omega, AXIS, "changing").iloc[0]
    assert gv["eig_ratio"] > 1e-8
    W = observability_gramian(sc.t[:n], sc.attitude.omega[:n])
    null = np.concatenate([np.zeros(3), AXIS, AXIS])
    assert np.linalg.norm(W @ null) < 1e-10 * np.linalg.norm(W)


def test_bad_input_is_rejected():
    sc = _scenario(_changing(1.0))
    s = sc.signals
    t = sc.t.copy()
    with pytest.raises(InputShapeError, match="uniformly sampled"):
        t2 = t.copy()
        t2[5] += 0.003
        kalman_filter(t2, s["a"], sc.attitude.omega, s["v"], np.zeros(9), P0)
    with pytest.raises(InputShapeError):
        kalman_filter(t, s["a"][:-1], sc.attitude.omega, s["v"], np.zeros(9), P0)
    a = s["a"].copy()
    a[3, 0] = np.inf
    with pytest.raises(NonFiniteError):
        kalman_filter(t, a, sc.attitude.omega, s["v"], np.zeros(9), P0)


def test_chunked_monte_carlo_merges_to_the_single_job_tables():
    """Runs split over jobs (run_streams per run number) merge to the numbers of one job;
    a chunk that drew the wrong runs' noise would not."""
    from accelcal_repro.batista2011.montecarlo import filter_summary, merge_filter_moments, run_streams

    sc = _scenario(_changing(20.0))
    kw = dict(record_every_s=5.0, summary_every_s=1.0)
    whole = filter_montecarlo(sc, run_streams(7, "filter", range(9)), P0, **kw)
    parts = [filter_montecarlo(sc, run_streams(7, "filter", ids), P0, run_ids=ids, **kw)
             for ids in (range(0, 4), range(4, 7), range(7, 9))]
    runs = __import__("pandas").concat([p.runs for p in parts], ignore_index=True)
    assert np.array_equal(runs.to_numpy(), whole.runs.to_numpy())
    merged = filter_summary(merge_filter_moments([p.moments for p in parts[::-1]]))  # order does not matter
    num = [c for c in whole.summary.columns if c != "state"]
    assert (merged["state"] == whole.summary["state"]).all() and (merged["n_runs"] == 9).all()
    np.testing.assert_allclose(merged[num].to_numpy(float), whole.summary[num].to_numpy(float), rtol=1e-12, atol=1e-15)
    # the same runs drawn from other streams give other numbers
    other = filter_montecarlo(sc, run_streams(8, "filter", range(9)), P0, **kw)
    assert not np.allclose(other.summary["mean_error"], whole.summary["mean_error"])
    with pytest.raises(ValueError, match="different summary times"):
        merge_filter_moments([parts[0].moments, parts[1].moments.iloc[:-9]])
