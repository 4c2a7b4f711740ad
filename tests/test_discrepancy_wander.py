"""The wander null of the discrepancy loop: wander covariance, REML, bootstrap tests, outliers.

Sessions are simulated at the pose level (the exact Gaussian law of the pose means: white
per-pose noise plus interval means of the wander, :func:`~accelcal.discrepancy.wander.
simulate_interval_means`), like the benchmark's session (30 poses of 5.5 s, 2 s moves,
a 20 s initial rest, 16-bit counts), so that a test can afford tens of recordings.  The
bounds are one-sided binomial bounds at fixed seeds: each fails if the method's rate is
far from its claim, not by chance (the numbers in the comments are the measured ones).
"""

import numpy as np
import pytest
from scipy import stats

from accelcal.discrepancy import wander as C
from accelcal.discrepancy import wander_loop as W
from accelcal.discrepancy.wander_model import linearise
from accelcal.discrepancy.detect import discrepancy
from accelcal.discrepancy.fit import effect_columns, evaluate, fit_at, forward, pose_data
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.statistics import critical_noncentrality
from accelcal.errors import NotConvergedError
from accelcal.evaluation import residual_sigma
from accelcal.model import m_from_params
from accelcal.noise import simulate_noise
from accelcal.simulation import random_directions

G = 9.80665
N_SAMPLE = 3.3          # counts, white noise per sample
RATE = 100.0
POSE_WHITE = N_SAMPLE / np.sqrt(5.5 * RATE)   # std of a pose mean's white noise (counts)
#: The issue's realistic wander: three Gauss-Markov components at the pose-mean white level.
THREE_GM = {"gauss_markov": [(POSE_WHITE, 3.0), (POSE_WHITE, 30.0), (POSE_WHITE, 300.0)]}
#: A rate random walk that moves the bias by about 3 pose-mean sigmas over 300 s.
RANDOM_WALK = {"random_walk": 3 * POSE_WHITE / np.sqrt(300.0)}


def design(n=30, init=20.0, rest=6.0, move=2.0, trim=0.25):
    starts, durs, t = [0.0], [init - trim], init + move
    for _ in range(1, n):
        starts.append(t + trim)
        durs.append(rest - 2 * trim)
        t += rest + move
    return np.array(starts), np.array(durs)


def session(rng, wander=None, n=30, effects=None, temp=None, outlier=None, axis_corr=None):
    """Pose data of one simulated session; returns (PoseData, truth dict).  ``axis_corr``: the
    wander's correlation between the sensor axes (default independent axes)."""
    a, T = design(n)
    u = random_directions(rng, n)
    s = 415 * (1 + rng.uniform(-0.01, 0.01, 3)) - 1
    th = np.deg2rad(rng.uniform(0.1, 1.5, 3) * rng.choice([-1, 1], 3))
    M, b = m_from_params(s, th), 32768 + rng.uniform(-600, 600, 3)
    tmid = a + T / 2
    if temp is None:  # two cycles over the session, random phase (the benchmark's)
        temp = 25 + 5 * np.sin(4 * np.pi * tmid / (a[-1] + T[-1]) + rng.uniform(0, 2 * np.pi))
    se = N_SAMPLE / np.sqrt(T * RATE)
    ms = np.repeat(se[:, None], 3, axis=1)
    z0 = forward(G * u, M, b, {})
    truth = dict(M=M, b=b, u=u, p=np.concatenate([b, s, th]), tmid=tmid, temp=temp, starts=a, durations=T,
                 sigma=residual_sigma(z0, ms, M, b))
    z = forward(G * u, M, b, effects or {}, dt=tmid - tmid.mean(), dtemp=temp - temp.mean())
    z = z + ms * rng.standard_normal((n, 3))
    if wander:
        z = z + C.simulate_interval_means(rng, wander, a, T, axis_corr=axis_corr)
    if outlier is not None:
        i, k = outlier  # shift pose i by k of its residual sigmas along gravity
        z[i] += k * truth["sigma"][i] * (M @ u[i])
    return pose_data(z, G, ms, tmid, temp, t_start=a, t_end=a + T), truth


def true_mde_direction(truth, eid, wander, rules, n_tests, direction):
    """Size along ``direction`` (unit) of the effect at its MDE under the true noise (white + wander)."""
    a, T = truth["starts"], truth["durations"]
    n = len(a)
    se = N_SAMPLE / np.sqrt(T * RATE)
    z0 = forward(G * truth["u"], truth["M"], truth["b"], {})
    d0 = pose_data(z0, G, np.repeat(se[:, None], 3, axis=1), truth["tmid"], truth["temp"], sigma=truth["sigma"],
                   t_start=a, t_end=a + T)
    f0 = fit_at(d0, (), truth["p"])
    prob = linearise(d0, f0)
    Xe = prob.columns(effect_columns(truth["p"], d0, (), eid))
    S = C.contrast_covariance(prob, wander or {})
    info = C.effect_information(prob, prob.X0, Xe, sigma_c=S).wander
    lam = critical_noncentrality(3, n - 12, rules.alpha / n_tests, rules.power)
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    return float(np.sqrt(lam / (d @ info @ d))) * d


# --------------------------------------------------------------------------- the covariance


def test_contrast_covariance_matches_simulated_time_series():
    """The wander's covariance in the contrasts (exact interval means, projected through the
    residual gradient) against pose means averaged from simulated time series of a
    Gauss-Markov bias: E[yᵀ Σ⁻¹ y] = m for the model's Σ, and white noise alone is far off."""
    rng = np.random.default_rng(0)
    n, fs, reps = 24, 10.0, 600
    a, T = design(n)
    u = random_directions(rng, n)
    M, b = m_from_params(np.full(3, 414.0), np.deg2rad([0.3, -0.5, 0.8])), np.array([32768.0, 32500, 33000])
    p = np.concatenate([b, np.full(3, 414.0), np.deg2rad([0.3, -0.5, 0.8])])
    se = np.repeat((0.05 / np.sqrt(T))[:, None], 3, axis=1)
    z0 = forward(G * u, M, b, {})
    tmid = a + T / 2
    d0 = pose_data(z0, G, se, tmid, t_start=a, t_end=a + T, sigma=residual_sigma(z0, se, M, b))
    f0 = fit_at(d0, (), p)
    prob = linearise(d0, f0)
    gm = (0.4, 40.0)
    S = C.contrast_covariance(prob, {"gauss_markov": gm})
    nt = int(np.ceil((a[-1] + T[-1]) * fs)) + 1
    ys = []
    for axis_noise in [simulate_noise(rng, nt, fs, {"gauss_markov": gm}, size=reps) for _ in range(3)]:
        idx = [np.arange(int(round(s * fs)), int(round((s + d) * fs))) for s, d in zip(a, T)]
        ys.append(np.stack([axis_noise[i].mean(axis=0) for i in idx]))  # (n, reps)
    wander = np.stack(ys, axis=2)  # (n, reps, 3)
    white = se[:, None, :] * rng.standard_normal((n, reps, 3))
    Sinv = np.linalg.inv(S)
    q_model, q_white = [], []
    for k in range(reps):
        z = z0 + wander[:, k] + white[:, k]
        res, _, _ = evaluate(p, pose_data(z, G, se, tmid, sigma=d0.sigma), ())
        y = prob.L.T @ (res / d0.sigma)
        q_model.append(y @ Sinv @ y)
        q_white.append(y @ y)
    m = prob.m
    # the model's quadratic form has mean m (SE sqrt(2m/reps), inflated a little by the
    # time-series discretisation); white noise alone would predict m too and is far off
    assert abs(np.mean(q_model) - m) < 4 * np.sqrt(2 * m / reps) + 0.03 * m, (np.mean(q_model), m)
    assert np.mean(q_white) > 3 * m


# --------------------------------------------------------------------------- false positives


def _outcomes(profile, reps, seed, rules):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(reps):
        d, _ = session(rng, profile)
        out.append((discrepancy(d, rules).outcome, discrepancy(d, Rules(null="white", candidates=rules.candidates))
                    .outcome))
    return out


#: Three candidates + the outlier family: a family of 4, so n_boot = 79 reaches α/4.
FAST = Rules(candidates=("quadratic", "bias_drift", "temperature"), n_boot=79)


def test_wander_null_keeps_false_positives_at_alpha_where_white_null_does_not():
    """Effect-free sessions whose only "effect" is wander: the issue's three Gauss-Markov
    components (3, 30, 300 s, each at the pose-mean white level) and a rate random walk.
    The wander null names something on at most 5 of 30 per profile (if its rate were 5 %,
    more than 5 has probability 0.008); the white null on the same 60 recordings names an
    effect at least 9 times (at 5 %, probability 0.007): the inflation of the issue."""
    named = lambda o: o not in ("none", "not_identifiable", "error")  # noqa: E731
    res = _outcomes(THREE_GM, 30, 1, FAST) + _outcomes(RANDOM_WALK, 30, 2, FAST)
    wander = [named(c) for c, _ in res]
    white = [named(w) for _, w in res]
    assert sum(wander[:30]) <= 5 and sum(wander[30:]) <= 5, (sum(wander[:30]), sum(wander[30:]))
    assert sum(white) >= 9, sum(white)
    assert stats.binom.sf(5, 30, 0.05) < 0.01 and stats.binom.sf(8, 60, 0.05) < 0.01


# --------------------------------------------------------------------------- axes that wander together


def _equicorrelated(rho):
    return np.full((3, 3), rho) + (1.0 - rho) * np.eye(3)


#: A strong common-mode wander: Gauss-Markov (10 pose sigmas, τ = 100 s) or a random walk
#: (10 pose sigmas over 300 s), correlated 0.95 between the three sensor axes.
COMMON_WANDERS = ({"gauss_markov": (10 * POSE_WHITE, 100.0)}, {"random_walk": 10 * POSE_WHITE / np.sqrt(300.0)})


def test_axis_gram_is_the_wander_covariance_through_the_gradients():
    """``∇_iᵀ C_φ ∇_j`` with ``C_φ = (1 − φ) I + φ 11ᵀ``; φ = 0 is the independent-axes kernel."""
    rng = np.random.default_rng(3)
    g = rng.standard_normal((7, 3))
    for phi in (0.0, 0.4, 1.0):
        np.testing.assert_allclose(C.axis_gram(g, phi), g @ _equicorrelated(phi) @ g.T, atol=1e-12)
        np.testing.assert_allclose(C.axis_weight(g, phi), np.diag(g @ _equicorrelated(phi) @ g.T), atol=1e-12)


def test_common_mode_wander_keeps_false_positives_at_alpha(monkeypatch):
    """Effect-free sessions whose wander is shared by the axes (correlation 0.95, the two
    wanders of :data:`COMMON_WANDERS`, 50 sessions each).  With the axis correlation
    estimated, something is named on at most 10 of 100 (at a 5 % rate, more than 10 has
    probability 0.011), and on fewer than with the axes held independent (the grid of φ
    cut to 0: the old null) on the same sessions (measured 4 vs 8 of 100; the old null's
    excess at this size is small: on phase-randomised surrogates of the ADIS16405 record,
    600 sessions, 37 vs 25 named, see the branch's report)."""
    named = lambda o: o not in ("none", "not_identifiable", "error")  # noqa: E731
    grid = C.COMMON_GRID
    counts = {}
    for label, g in (("estimated", grid), ("independent", np.array([0.0]))):
        monkeypatch.setattr(C, "COMMON_GRID", g)
        monkeypatch.setattr(C.reml, "COMMON_GRID", g)   # fit_common's default grid
        n = 0
        for k, wander in enumerate(COMMON_WANDERS):
            rng = np.random.default_rng(40 + k)
            for _ in range(50):
                d, _ = session(rng, wander, axis_corr=_equicorrelated(0.95))
                n += named(discrepancy(d, FAST).outcome)
        counts[label] = n
    assert counts["estimated"] <= 10 and counts["estimated"] < counts["independent"], counts
    assert stats.binom.sf(10, 100, 0.05) < 0.012


def test_axis_correlation_estimate_follows_the_planted_one():
    """A Gauss-Markov wander (10 pose sigmas, τ = 100 s) correlated 0, 0.5 or 0.95 between
    the axes, 24 sessions each: the median estimate is within one step of the grid of φ of
    the planted correlation, the medians are ordered, and the 95 % grid interval (widened
    by a step where the truth is between grid values) holds the truth on at least 18 of 24
    (measured medians 0, 0.33, 1.0: from one session the estimate is rough; with 12 sessions
    the median of the uncorrelated wander sat on the boundary between 0 and 1/3, 0.17 or
    0.33 depending on one session)."""
    wander = COMMON_WANDERS[0]
    step = float(np.max(np.diff(C.COMMON_GRID)))
    med = []
    for k, rho in enumerate((0.0, 0.5, 0.95)):
        rng = np.random.default_rng(60 + k)
        est, cover = [], 0
        on_grid = bool(np.any(np.isclose(C.COMMON_GRID, rho)))
        for _ in range(24):
            d, _ = session(rng, wander, axis_corr=_equicorrelated(rho))
            nm = discrepancy(d, FAST).noise_model
            est.append(nm["axis_correlation"])
            lo, hi = nm["axis_correlation_ci"]
            cover += lo <= rho <= hi if on_grid else lo - step < rho < hi + step
        med.append(float(np.median(est)))
        assert abs(med[-1] - rho) <= step + 1e-12 and cover >= 18, (rho, est, cover)
    assert med[0] < med[1] < med[2], med


# --------------------------------------------------------------------------- power, naming


@pytest.mark.parametrize("eid", ["quadratic", "bias_drift", "temperature"])
def test_effect_at_three_times_its_mde_is_named_under_the_wander(eid):
    """A Gauss-Markov wander (2 pose sigmas, τ = 60 s) plus one effect at 3x its MDE under
    that noise, along a random direction: named first on at least 7 of 8 recordings
    (at the design's power, ≥ 0.99 per recording at 3 MDE)."""
    rng = np.random.default_rng(10 + len(eid))
    wander = {"gauss_markov": (2 * POSE_WHITE, 60.0)}
    rules = FAST
    hits = []
    for _ in range(8):
        _, truth = session(np.random.default_rng(rng.integers(1 << 30)), wander)  # the design
        phi = 3.0 * true_mde_direction(truth, eid, wander, rules, 3, rng.standard_normal(3))
        data, _ = _session_like(truth, rng, wander, {eid: phi})  # effect and noise on that design
        hits.append(discrepancy(data, rules).effect == eid)
    assert sum(hits) >= 7, hits


def _session_like(truth, rng, wander, effects, outlier=None):
    a, T, u, M, b = truth["starts"], truth["durations"], truth["u"], truth["M"], truth["b"]
    tmid, temp = truth["tmid"], truth["temp"]
    se = N_SAMPLE / np.sqrt(T * RATE)
    ms = np.repeat(se[:, None], 3, axis=1)
    z = forward(G * u, M, b, effects, dt=tmid - tmid.mean(), dtemp=temp - temp.mean())
    z = z + ms * rng.standard_normal(z.shape)
    if wander:
        z = z + C.simulate_interval_means(rng, wander, a, T)
    if outlier is not None:
        i, k = outlier
        z[i] += k * truth["sigma"][i] * (M @ u[i])
    return pose_data(z, G, ms, tmid, temp, t_start=a, t_end=a + T), truth


def test_wander_estimate_covers_the_simulated_size_and_time_constant():
    """A single Gauss-Markov wander (3 pose sigmas, τ = 60 s) on 40 poses: the 95 % profile
    intervals of τ and of the size contain the truth on at least 8 of 10 recordings."""
    rng = np.random.default_rng(5)
    s, tau = 3 * POSE_WHITE, 60.0
    cover_tau, cover_s, taus = 0, 0, []
    for _ in range(10):
        d, _ = session(rng, {"gauss_markov": (s, tau)}, n=40)
        nm = discrepancy(d, FAST).noise_model
        assert nm["term"] == "bias_wander"
        lo, hi = nm["tau_ci"]
        cover_tau += lo <= tau <= hi
        lo, hi = nm["size_ci"]
        cover_s += lo <= s <= hi
        taus.append(nm["tau_s"])
    assert cover_tau >= 8 and cover_s >= 8, (cover_tau, cover_s, taus)
    assert 20 < np.median(taus) < 180, taus


def test_outlier_pose_is_named_with_its_index_and_removed():
    """One pose shifted by 12 of its white sigmas (about 6.5 sigmas of the whole noise) in a
    session with the realistic wander: named `outlier_pose` with its index and time, on at
    least 3 of 4 recordings (12 of 12 measured with all candidates; at 8 white sigmas 6 of
    12: the max-LR family over 30 poses under the wander needs about 4.5 sigmas); the gap
    shrinks without it and the report keeps the pose, marked excluded."""
    found = 0
    for seed in range(4):
        rng = np.random.default_rng(100 + seed)
        d, truth = session(rng, THREE_GM, outlier=(17, 12.0))
        res = discrepancy(d, FAST)
        out = res.to_dict()
        if res.outcome == W.OUTLIER:
            o = out["outliers"][0]
            found += o["pose"] == 17
            assert o["t"] == pytest.approx(truth["tmid"][17])
            assert o["gap_after"] < o["gap_before"]
            assert abs(o["shift_sigma"]) > 6
            assert out["poses"]["excluded"] == [17] and len(out["poses"]["residual_after"]) == 30
    assert found >= 3, found


def test_two_effects_are_both_named():
    """Quadratic and temperature, each at 3x its MDE under the noise (white + the realistic
    wander), in the same session, random directions.  Whenever the loop names one of them
    first it names the other in the next round (the second effect keeps its power once the
    first is in the model: 13 of 13 in a run of 16), and both are named on at least 5 of 8
    recordings (13 of 16 measured; the misses name nothing: in round 1 each effect is
    tested with the other one unmodelled, which inflates the fitted wander)."""
    rules = Rules(candidates=("quadratic", "cubic", "bias_drift", "temperature"), n_boot=199)
    both = first = 0
    for seed in range(8):
        rng = np.random.default_rng(200 + seed)
        _, truth = session(np.random.default_rng(300 + seed), None)
        phi_q = 3 * true_mde_direction(truth, "quadratic", THREE_GM, rules, 4, rng.standard_normal(3))
        phi_t = 3 * true_mde_direction(truth, "temperature", THREE_GM, rules, 4, rng.standard_normal(3))
        d, _ = _session_like(truth, rng, THREE_GM, {"quadratic": phi_q, "temperature": phi_t})
        res = discrepancy(d, rules)
        first += res.effect in ("quadratic", "temperature")
        both += set(res.effects) >= {"quadratic", "temperature"}
    assert both == first and both >= 5, (both, first)


def test_temperature_that_follows_time_cannot_be_told_from_a_drift():
    """A temperature that rises steadily with time and a large bias drift: the two
    signatures coincide, so neither is named; both are not identifiable, with the reason."""
    rng = np.random.default_rng(7)
    a, T = design(30)
    tmid = a + T / 2
    temp = 20 + 10 * tmid / tmid[-1]  # a warm-up linear in time
    _, truth = session(np.random.default_rng(8), None, temp=temp)
    phi = 6 * true_mde_direction(truth, "bias_drift", None, Rules(), 5, [1.0, 0.5, -0.5])
    d, _ = _session_like(truth, rng, None, {"bias_drift": phi})
    res = discrepancy(d, Rules())
    assert res.outcome == "not_identifiable", res.effects
    reasons = res.not_identifiable_reasons
    assert {"bias_drift", "temperature"} <= set(reasons)
    assert any("told apart" in r for r in reasons["bias_drift"])


# --------------------------------------------------------------------------- bad input


def test_too_few_poses_for_the_wander_is_stated_not_replaced_by_white():
    rng = np.random.default_rng(9)
    d, _ = session(rng, None, n=11)
    res = discrepancy(d, Rules())
    nm = res.to_dict()["noise_model"]
    assert nm["estimated"] is False and "poses" in nm["reason"]
    assert res.outcome == "not_identifiable" and not res.effects
    assert all("bias wander cannot be estimated" in " ".join(c.reasons) for c in res.candidates)


def test_a_fit_that_does_not_converge_is_an_error_not_none(monkeypatch):
    rng = np.random.default_rng(11)
    d, _ = session(rng, None)
    real = W.fit

    def failing(data, effects=(), p0=None, max_iter=200):
        if effects:
            raise NotConvergedError(f"model base+{'+'.join(effects)} did not converge in 200 iterations")
        return real(data, effects, p0, max_iter)

    monkeypatch.setattr(W, "fit", failing)
    res = discrepancy(d, FAST)
    out = res.to_dict()
    assert res.outcome == "error" and out["outcome"] == "error"
    assert any("did not converge" in e for e in out["errors"])


def test_bootstrap_too_small_for_the_family_is_refused():
    with pytest.raises(Exception, match="n_boot"):
        Rules(n_boot=99)  # 5 candidates + outliers: Holm's first level 0.05/6 < 1/100
    Rules(n_boot=99, null="white")  # the white null has no bootstrap


# --------------------------------------------------------------------------- the output contract


def test_json_keeps_the_old_keys_and_adds_the_new_ones():
    import json

    from accelcal.jsonsafe import json_safe

    rng = np.random.default_rng(12)
    d, _ = session(rng, THREE_GM)
    out = json.loads(json.dumps(json_safe(discrepancy(d, FAST).to_dict())))
    for k in ("effect", "effects", "outcome", "not_identifiable", "candidates", "gap_before", "gap_after",
              "gap_expected_before", "gap_lopo_before", "excess_before", "excess_after", "excess_status",
              "model_before", "model_after", "poses", "rules"):
        assert k in out, k
    for k in ("null", "noise_model", "outliers", "outlier_tests", "not_identifiable_reasons", "errors",
              "gap_wander_before", "gap_wander_after", "excess_predicted", "excess_observed"):
        assert k in out, k
    nm = out["noise_model"]
    for k in ("term", "process", "size", "size_ci", "tau_s", "tau_ci", "random_walk_K", "method",
              "axis_correlation", "axis_correlation_ci", "axis_correlation_profile"):
        assert k in nm, k
    assert 0.0 <= nm["axis_correlation"] <= 1.0 and len(nm["axis_correlation_profile"]) == len(C.COMMON_GRID)
    assert out["rules"]["null"] == "wander"
    white = json_safe(discrepancy(d, Rules(null="white")).to_dict())
    assert white["null"] == "white" and white["noise_model"]["estimated"] is False
