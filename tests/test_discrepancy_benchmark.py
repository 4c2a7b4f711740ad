"""Benchmark of the discrepancy loop: plan and streams, noise profiles against their covariance,
the oracle MDE, key/detection separation, and a scoring that catches deliberately wrong detectors."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from accelcal.discrepancy import rules as D
from accelcal.discrepancy import white_loop
from accelcal.effects import EFFECT_IDS
from accelcal.formats import read, write_recording
from accelcal_repro.discrepancy import benchmark as B
from accelcal_repro.discrepancy import profiles as P
from accelcal_repro.discrepancy import record_screen as RS
from accelcal_repro.discrepancy import scoring as S

SESSION = B.Session()
RULES = D.Rules()
WHITE_RULES = B.rules_with_null(RULES, "white")
SEED = 11
PROFILES = P.build_profiles([{"name": "white"}, {"name": "gm_3x_session", "gauss_markov": [[3.0, "session"]]},
                             {"name": "rounding", "noise_counts": 0.35},
                             {"name": "gm_mix", "gauss_markov": [[1.0, 3.0], [1.0, 30.0], [1.0, 300.0]]}], SESSION)
WHITE = PROFILES["white"]


def test_plan_chunks_partition_the_plan():
    plan = B.plan(["white", "gm"], EFFECT_IDS, [1.0, 3.0], 3, 5, 2, pairs=[("quadratic", "temperature")],
                  extra_sizes={"white": [0.5]})
    k = len(EFFECT_IDS)
    per_profile = 5 + k * 2 * 3 + 2 * 3 + 2 * 3 + 2
    assert len(plan) == 2 * per_profile + k * 3 and plan.recording.is_unique
    assert set(plan.truth) == {B.NONE, *EFFECT_IDS, "quadratic+temperature", B.OUTLIER, B.CONSTANT_TEMPERATURE}
    parts = [B.chunk(plan, 4, k) for k in range(4)]
    assert sorted(pd.concat(parts).recording) == sorted(plan.recording)
    with pytest.raises(Exception):
        B.chunk(plan, 4, 4)
    with pytest.raises(Exception, match="unknown benchmark row"):
        B.plan(["white"], ["nonsense"], [1.0], 1, 1, 0)
    # a real-record profile gets its own number of effect-free recordings
    counts = B.plan(["white", "adis_real"], EFFECT_IDS, [3.0], 1, 5, 0, none_counts={"adis_real": 7}
                    ).query("truth == @B.NONE").groupby("profile").size()
    assert counts.to_dict() == {"white": 5, "adis_real": 7}


def test_each_recording_has_its_own_stream():
    """Same profile, row and replicate -> identical recording; different -> different."""
    a, ka = B.simulate_case("quadratic", 2.0, 3, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
    b, kb = B.simulate_case("quadratic", 2.0, 3, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
    c, _ = B.simulate_case("quadratic", 2.0, 4, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
    np.testing.assert_array_equal(a.acc, b.acc)
    assert ka == kb
    assert not np.array_equal(a.acc, c.acc)
    np.testing.assert_array_equal(a.acc, np.round(a.acc))  # raw counts, as a 16-bit sensor writes them
    d = np.array([ka[f"direction_quadratic_{x}"] for x in "xyz"])
    phi = np.array([ka[f"param_quadratic_{x}"] for x in "xyz"])
    np.testing.assert_allclose(phi, 2.0 * ka["mde_along_quadratic"] * d)


def test_oracle_mde_is_the_loops_own_under_white_noise_and_larger_under_wander():
    _, kw = B.simulate_case("bias_drift", 1.0, 0, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
    assert kw["mde_along_bias_drift"] == pytest.approx(kw["mde_along_white_bias_drift"], rel=1e-9)
    _, kg = B.simulate_case("bias_drift", 1.0, 0, seed=SEED, session=SESSION, rules=RULES,
                            profile=PROFILES["gm_3x_session"])
    # a bias wandering over the whole session hides a drift: its oracle MDE is several times the white one
    assert kg["mde_along_bias_drift"] > 2.0 * kg["mde_along_white_bias_drift"]


def _pose_means(rec):
    win = SESSION.trimmed_windows(len(rec.t))
    return np.array([rec.acc[a:b].mean(axis=0) for a, b in win])


@pytest.mark.parametrize("name", ["gm_mix", "rounding"])
def test_profile_noise_matches_its_pose_mean_covariance(name):
    """The centred pose-mean variance of simulated noise agrees with pose_mean_covariance
    (Monte Carlo over 300 sessions, each pose and axis; chi-square-size tolerance)."""
    prof = PROFILES[name]
    n = SESSION.n_samples
    win = SESSION.trimmed_windows(n)
    ns = (win[:, 1] - win[:, 0]).astype(float)
    C = P.pose_mean_covariance(prof, win[:, 0] / SESSION.rate, ns / SESSION.rate, ns, SESSION.rate)
    Pc = np.eye(len(ns)) - 1.0 / len(ns)
    want = float(np.mean([np.diag(Pc @ C[a] @ Pc).mean() for a in range(3)]))
    rng = np.random.default_rng(1)
    got = []
    for _ in range(300):
        noise = P.simulate_profile(prof, rng, n, SESSION.rate)
        # the true value of each pose falls anywhere between two counts
        frac = rng.uniform(0, 1, (len(ns), 3))
        m = np.array([np.round(noise[a:b] + frac[i]).mean(axis=0) - frac[i] for i, (a, b) in enumerate(win)])
        got.append(((m - m.mean(axis=0)) ** 2).mean())
    got = float(np.mean(got))
    assert got == pytest.approx(want, rel=0.08), (got, want)


def test_rounding_bias_is_what_sub_count_noise_leaves():
    assert P.rounding_bias_variance(3.3) < 1e-12  # the Xsens-like session: rounding averages out
    rng = np.random.default_rng(2)
    f = rng.uniform(0, 1, 4000)
    means = np.round(f[:, None] + 0.3 * rng.standard_normal((4000, 2000))).mean(axis=1) - f
    assert np.var(means) - 0.3 ** 2 / 2000 == pytest.approx(P.rounding_bias_variance(0.3), rel=0.1)


def test_real_profile_draws_disjoint_windows():
    rec = np.arange(10 * 3, dtype=float).reshape(10, 3)
    prof = P.NoiseProfile("r", (1.0, 1.0, 1.0), (), real="adis16405", real_scale=(1.0, 2.0, 3.0), kind="real")
    rng = np.random.default_rng(0)
    w0 = P.simulate_profile(prof, rng, 4, 100.0, replicate=0, records={"adis16405": rec})
    w1 = P.simulate_profile(prof, rng, 4, 100.0, replicate=1, records={"adis16405": rec})
    w2 = P.simulate_profile(prof, rng, 4, 100.0, replicate=2, records={"adis16405": rec})  # window 0, axes permuted
    np.testing.assert_array_equal(w0, rec[:4] * [1, 2, 3])
    np.testing.assert_array_equal(w1, rec[4:8] * [1, 2, 3])
    assert not np.array_equal(w2, w0) and sorted(w2[0] / [1, 2, 3]) == sorted(rec[0])
    with pytest.raises(P.ProfileError, match="needs the adis16405 noise record"):
        P.simulate_profile(prof, rng, 4, 100.0)


def test_axis_correlation_of_a_profile_is_what_the_axes_share():
    """A profile whose wander is correlated between the axes by phi (the joint model's common-mode
    share) gives that correlation, keeps each axis's variance, round-trips, and refuses axes of
    different models; phi = 0 is the independent-axes stream, unchanged."""
    comps = (("gauss_markov", ((1.0, 0.5),) * 3),)
    prof = P.NoiseProfile("c", (0.0, 0.0, 0.0), comps, axis_correlation=0.6)
    x = P.simulate_profile(prof, np.random.default_rng(3), 200_000, 100.0)
    c = np.corrcoef(x.T)
    assert np.allclose(c[np.triu_indices(3, 1)], 0.6, atol=0.05), c
    assert np.allclose(x.std(axis=0), 1.0, rtol=0.05)
    assert P.NoiseProfile.from_dict(prof.to_dict()) == prof
    indep = dataclasses.replace(prof, axis_correlation=0.0)
    assert np.abs(np.corrcoef(P.simulate_profile(indep, np.random.default_rng(3), 200_000, 100.0).T)[0, 1]) < 0.05
    mixed = P.NoiseProfile("m", (0.0, 0.0, 0.0), (("gauss_markov", ((1.0, 0.5), (2.0, 0.5), (1.0, 0.5))),),
                           axis_correlation=0.5)
    with pytest.raises(P.ProfileError, match="same gauss_markov on every axis"):
        P.simulate_profile(mixed, np.random.default_rng(0), 10, 100.0)


def test_profile_config_errors_are_one_line():
    with pytest.raises(P.ProfileError, match="unknown keys"):
        P.build_profiles([{"name": "x", "gauss_marko": [[1, 3]]}], SESSION)
    with pytest.raises(P.ProfileError, match="no noise model of xsens_mti"):
        P.build_profiles([{"name": "x", "fitted": "xsens_mti"}], SESSION)
    with pytest.raises(P.ProfileError, match="stands alone"):
        P.build_profiles([{"name": "x", "fitted": "adis16405", "random_walk": 1.0}], SESSION, fitted={"adis16405": {}})
    with pytest.raises(P.ProfileError, match="distinct name"):
        P.build_profiles([{"name": "x"}, {"name": "x"}], SESSION)


def test_detection_reads_only_the_recording_and_the_csv_gives_the_same(tmp_path):
    rec, key = B.simulate_case("bias_drift", 3.0, 0, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
    rows = B.detect_nulls(rec, SESSION.g, RULES, ("white",))
    assert not set(rows[0]) & {"truth", "expected", "size_mde", "param_bias_drift_x", "profile"}
    assert rows[0]["outcome"] == "bias_drift"
    write_recording(tmp_path / "r.csv", rec)
    again = B.detect_nulls(read(tmp_path / "r.csv", strict=True), SESSION.g, RULES, ("white",))
    assert again[0]["outcome"] == rows[0]["outcome"]
    assert again[0]["gap_before"] == pytest.approx(rows[0]["gap_before"], rel=1e-9)


def _benchmark(rows, rules, profile=WHITE, seed=SEED):
    keys, dets = [], []
    for truth, size, rep in rows:
        rec, key = B.simulate_case(truth, size, rep, seed=seed, session=SESSION, rules=RULES, profile=profile)
        name = f"{profile.name}__{truth}_{size:g}_{rep:04d}"
        keys.append({"recording": name, **key})
        dets.append({"recording": name, **B.detect_case(rec, SESSION.g, rules)})
    scores = S.score_cases(pd.DataFrame(keys), pd.DataFrame(dets))
    rates = S.rates(scores)
    return scores, S.summary(scores, rates, alpha=RULES.alpha, power=RULES.power)


def _verdict(summary, effect, metric):
    r = summary[(summary.effect == effect) & (summary.metric == metric)]
    assert len(r) == 1
    return r.iloc[0]


NULL_ROWS = [(B.NONE, 0.0, r) for r in range(60)]


def test_scoring_catches_a_test_without_multiple_comparison_control():
    """Five candidates each at level α with no Holm, no ΔBIC and no LOPO rule: about
    1 - 0.95⁵ ≈ 23 % of effect-free recordings get an effect named; the scoring's
    false-positive verdict fails.  The real rules on the same recordings pass."""
    wrong = dataclasses.replace(WHITE_RULES, correction="none", bic_threshold=-np.inf, lopo_min_improvement=-np.inf)
    _, bad = _benchmark(NULL_ROWS, wrong)
    fp_bad = _verdict(bad, B.NONE, "false_positive_rate")
    assert fp_bad.verdict == "fail" and fp_bad.ci_low > RULES.alpha, fp_bad
    _, good = _benchmark(NULL_ROWS, WHITE_RULES)
    fp = _verdict(good, B.NONE, "false_positive_rate")
    assert fp.value < fp_bad.value and fp.ci_low <= RULES.alpha


def test_scoring_catches_a_fitter_that_ignores_the_effect(monkeypatch):
    """A fitter that returns the current model for current + effect (effect fixed at 0) never
    sees anything: accuracy at >= 1 MDE collapses and the scoring's verdict fails."""
    rows = [(e, 3.0, r) for e in EFFECT_IDS for r in range(3)]
    # the blind fitter replaces the nonlinear fit the white null's F-test compares; the wander
    # null tests on the linearised columns (tests/test_discrepancy_wander.py checks it)
    _, good = _benchmark(rows, WHITE_RULES)
    assert all(_verdict(good, e, "accuracy_ge_1mde").verdict == "pass" for e in EFFECT_IDS)

    real_fit = white_loop.fit

    def blind_fit(data, effects=(), p0=None, max_iter=200):
        base = real_fit(data, effects[:-1], p0=None if p0 is None else p0[: 9 + 3 * (len(effects) - 1)])
        if not effects:
            return base
        from accelcal.discrepancy.fit import fit_at

        return fit_at(data, effects, np.concatenate([base.p, np.zeros(3)]))

    monkeypatch.setattr(white_loop, "fit", blind_fit)
    _, bad = _benchmark(rows, WHITE_RULES)
    for e in EFFECT_IDS:
        v = _verdict(bad, e, "accuracy_ge_1mde")
        assert v.verdict == "fail" and v.value == 0.0, v


def _key(truth, **kw):
    return {"recording": truth, "profile": "p", "truth": truth, "expected": B.expected_outcome(truth),
            "effects_injected": "+".join(B.effects_of(truth)) or B.NONE, "size_mde": 3.0, "noise_window": -1,
            "outlier_t": kw.get("outlier_t", np.nan)}


def test_scoring_of_pairs_outliers_and_none():
    keys = pd.DataFrame([_key("quadratic+temperature"), _key("quadratic+cubic"), _key(B.OUTLIER, outlier_t=100.0),
                         _key("bias_drift"), _key(B.NONE)])
    dets = pd.DataFrame([
        {"recording": "quadratic+temperature", "null": "c", "outcome": "temperature", "effects": "temperature+quadratic"},
        {"recording": "quadratic+cubic", "null": "c", "outcome": "quadratic", "effects": "quadratic+bias_drift"},
        {"recording": B.OUTLIER, "null": "c", "outcome": B.OUTLIER, "effects": "", "outlier_t_detected": "250.000"},
        {"recording": "bias_drift", "null": "c", "outcome": "bias_drift", "effects": "bias_drift"},
        {"recording": B.NONE, "null": "c", "outcome": B.OUTLIER, "effects": "", "outlier_t_detected": "12.000"},
    ])
    sc = S.score_cases(keys, dets).set_index("recording")
    assert sc.loc["quadratic+temperature", "correct"]          # both, in any order
    assert not sc.loc["quadratic+cubic", "correct"] and sc.loc["quadratic+cubic", "detected"]  # one of two + a wrong one
    assert not sc.loc[B.OUTLIER, "correct"]                    # named at the wrong pose
    assert sc.loc["bias_drift", "correct"]
    assert sc.loc[B.NONE, "false_positive"]                    # an outlier named on an effect-free session
    dets.loc[2, "outlier_t_detected"] = "99.000;250.000"
    assert S.score_cases(keys, dets).set_index("recording").loc[B.OUTLIER, "correct"]


def test_outlier_scoring_survives_the_csv_round_trip(tmp_path):
    """The detection tables go through CSV (workflow/scripts/discrepancy_score.py reads them
    back with pandas): a chunk whose named outliers are one pose each comes back with
    ``outlier_t_detected`` as floats, and the outlier named at the right pose must still be
    scored correct (it was not: 0.08-0.25 accuracy at 3 MDE at the default config, 1.0 once
    rescored)."""
    keys = pd.DataFrame([_key(B.OUTLIER, outlier_t=208.995) | {"recording": "o1"},
                         _key(B.OUTLIER, outlier_t=100.0) | {"recording": "o2"},
                         _key(B.OUTLIER, outlier_t=50.0) | {"recording": "o3"}])
    dets = pd.DataFrame([
        {"recording": "o1", "null": "c", "outcome": B.OUTLIER, "effects": B.OUTLIER, "outlier_t_detected": "209.000"},
        {"recording": "o2", "null": "c", "outcome": B.OUTLIER, "effects": B.OUTLIER, "outlier_t_detected": "250.000"},
        {"recording": "o3", "null": "c", "outcome": B.NONE, "effects": "", "outlier_t_detected": ""},
    ])
    dets.to_csv(tmp_path / "chunk.csv", index=False)
    back = pd.read_csv(tmp_path / "chunk.csv", keep_default_na=False, na_values=[""])
    assert pd.api.types.is_float_dtype(back["outlier_t_detected"])  # what made the scoring miss it
    for d in (dets, back):
        sc = S.score_cases(keys, d).set_index("recording")
        assert sc.loc["o1", "correct"] and sc.loc["o1", "outlier_located"]
        assert not sc.loc["o2", "correct"]                     # the wrong pose
        assert not sc.loc["o3", "correct"]                     # nothing named


def test_effective_sample_size_of_clustered_outcomes():
    x = np.r_[np.ones(10), np.zeros(30)]
    assert S.effective_n(x) == 40
    # outcomes identical within each of 4 windows: as informative as 4 recordings
    assert S.effective_n(x, np.repeat(np.arange(4), 10)) == pytest.approx(4.0)
    # outcomes unrelated to the windows: about as informative as 40
    rng = np.random.default_rng(0)
    y = rng.random(400) < 0.3
    assert S.effective_n(y, np.tile(np.arange(40), 10)) > 300
    lo, hi, ne = S.interval(x, np.repeat(np.arange(4), 10))
    assert ne == pytest.approx(4.0) and hi - lo > 0.7


def test_crossing_and_intervals():
    assert S.crossing([0.5, 1, 2], [0.2, 0.5, 0.9], 0.5) == (pytest.approx(1.0), "")
    s, _ = S.crossing([1, 2], [0.4, 0.8], 0.6)
    assert s == pytest.approx(np.sqrt(2))  # midway in log(size)
    assert np.isnan(S.crossing([1, 2], [0.96, 1.0], 0.95)[0])
    assert np.isnan(S.crossing([1, 2], [0.1, 0.2], 0.5)[0])
    lo, hi = S.clopper_pearson(5, 100)
    assert lo == pytest.approx(0.01643, abs=1e-4) and hi == pytest.approx(0.11284, abs=1e-4)
    lo, hi = S.clopper_pearson(0, 10)
    assert lo == 0 and hi == pytest.approx(0.30850, abs=1e-4)


# --------------------------------------------------------------------------- screening a real record

FS = 100.0
N_WIN = 10_000  # 100 s windows


def _record(seed=3, n_windows=20):
    """White noise with a slow random-walk wander on each axis: a clean 'real' record."""
    rng = np.random.default_rng(seed)
    n = n_windows * N_WIN
    return rng.standard_normal((n, 3)) + np.cumsum(rng.standard_normal((n, 3)), axis=0) * 2e-3


def test_screen_leaves_a_clean_record_alone():
    rec = _record()
    assert RS.transient_scan(rec, FS, RS.RecordScreen()) == []
    assert RS.clean_windows(len(rec), N_WIN, []) == tuple(range(20))


@pytest.mark.parametrize("kind", ["bump", "step", "spike"])
def test_screen_finds_a_planted_transient_and_removes_its_window(kind):
    """A 5 s bump of 0.5 sd (11 sd of a 5 s mean), a step of 1 sd and a one-sample spike that moves a
    5 s mean by 10 of its sd, each planted in window 7 on one axis, are found there and nowhere else."""
    rec = _record()
    at = 7 * N_WIN + 4_000
    if kind == "bump":
        rec[at:at + 500, 1] += 0.5
    elif kind == "step":
        rec[at:, 2] += 1.0
    else:
        rec[at, 0] += 10 * 500 / np.sqrt(500)
    events = RS.transient_scan(rec, FS, RS.RecordScreen())
    assert events and {ev["start"] // N_WIN for ev in events} == {7}
    assert {ev["axis"] for ev in events} == {{"bump": 1, "step": 2, "spike": 0}[kind]}
    assert all(ev["start"] <= at + 500 and ev["stop"] >= at for ev in events)
    assert RS.clean_windows(len(rec), N_WIN, events) == tuple(k for k in range(20) if k != 7)


def test_screened_real_profile_draws_only_clean_windows():
    rec = _record()
    rec[7 * N_WIN + 4_000:7 * N_WIN + 4_500, :] += 0.5  # a bump on every axis in window 7
    fitted = {"adis16405": {"models": [{"white": 1.0 / np.sqrt(FS)}] * 3, "fs": FS, "white_match": False}}
    session = dataclasses.replace(SESSION, n_poses=12)  # 20 + 11 * 8 = 108 s: nine windows
    n = session.n_samples
    records = {"adis16405": rec}
    prof = P.build_profiles([{"name": "r", "real": "adis16405"}], session, fitted=fitted, records=records,
                            screen=RS.RecordScreen())["r"]
    bad = {(7 * N_WIN + 4_000) // n, (7 * N_WIN + 4_499) // n}
    assert prof.real_windows == tuple(k for k in range(len(rec) // n) if k not in bad)
    assert P.NoiseProfile.from_dict(prof.to_dict()) == prof
    assert P.independent_recordings(prof, 200, len(rec), n) == len(prof.real_windows)
    w = len(prof.real_windows)
    for r in (0, 5, w + 2):  # every replicate lands on a clean window (the last one: axes permuted)
        k, perm = P.window_of(prof, r, len(rec), n)
        assert k == prof.real_windows[r % w] and perm == P.AXIS_PERMUTATIONS[r // w]
        x = P.simulate_profile(prof, np.random.default_rng(0), n, FS, replicate=r, records=records)
        np.testing.assert_array_equal(x, rec[k * n:(k + 1) * n][:, list(perm)])
    unscreened = P.build_profiles([{"name": "r", "real": "adis16405"}], session, fitted=fitted)["r"]
    assert unscreened.real_windows == () and P.window_of(unscreened, 7, len(rec), n)[0] == 7


def test_record_screen_errors_are_one_line():
    with pytest.raises(RS.RecordScreenError, match="block_s > 0"):
        RS.RecordScreen(block_s=(0.0,))
    with pytest.raises(RS.RecordScreenError, match="fewer than two blocks"):
        RS.transient_scan(np.zeros((300, 3)), FS, RS.RecordScreen())
    with pytest.raises(RS.RecordScreenError, match="shape"):
        RS.transient_scan(np.zeros((3000, 2)), FS, RS.RecordScreen())
    with pytest.raises(RS.RecordScreenError, match="no scatter"):
        RS.transient_scan(np.zeros((30_000, 3)), FS, RS.RecordScreen())
    fitted = {"adis16405": {"models": [{"white": 0.1}] * 3, "fs": FS}}
    with pytest.raises(P.ProfileError, match="needs the adis16405 noise record"):
        P.build_profiles([{"name": "r", "real": "adis16405"}], SESSION, fitted=fitted, screen=RS.RecordScreen())
    prof = P.NoiseProfile("r", (1.0,) * 3, real="adis16405", real_windows=(0, 9), kind="real")
    with pytest.raises(P.ProfileError, match="beyond the 2 windows"):
        P.window_of(prof, 0, 2 * N_WIN, N_WIN)


def test_a_designs_owed_noise_draw_keeps_the_stream(monkeypatch):
    """The noise-free design leaves its (zero-weighted) noise draw owing and makes it only when
    its generator draws again: a redrawn design and an outlier pose see the stream they saw
    when the draw was made at once (the recordings and keys are the same)."""
    import accelcal.simulation as sim

    def refuse_first(real):  # the first design is not identifiable: the redraw path runs
        calls = {"n": 0}

        def ident(*args, **kwargs):
            calls["n"] += 1
            out = real(*args, **kwargs)
            return dataclasses.replace(out, identifiable=False) if calls["n"] == 1 else out
        return ident

    def case():
        monkeypatch.setattr(B, "identifiability", refuse_first(B.identifiability))
        rec, key = B.simulate_case(B.OUTLIER, 3.0, 0, seed=SEED, session=SESSION, rules=RULES, profile=WHITE)
        monkeypatch.undo()
        return rec, key

    rec, key = case()
    real_sim = sim.simulate_recording
    monkeypatch.setattr(B, "simulate_recording", lambda *a, draw_noise=True, **k: real_sim(*a, **k))
    monkeypatch.setattr(B, "_owed_draw", lambda rng, n: None)  # the draw made at once, as before
    rec0, key0 = case()
    assert key["redraws"] == key0["redraws"] == 1 and key["outlier_pose"] == key0["outlier_pose"]
    assert np.array_equal(rec.acc, rec0.acc) and key == key0
