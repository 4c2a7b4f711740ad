"""The benchmark's oracle (the loop's tests with the true noise covariance), the per-placement
profile, and the scoring of the loop against the oracle."""

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from accelcal.discrepancy import rules as D
from accelcal.discrepancy.fit import fit, pose_data_from_static
from accelcal.static import detect_static_recording
from accelcal_repro.discrepancy import benchmark as B
from accelcal_repro.discrepancy import profiles as P
from accelcal_repro.discrepancy import scoring as S
from accelcal_repro.discrepancy.oracle import named_set, oracle_detection

SESSION = B.Session()
RULES = D.Rules()
PROFILES = P.build_profiles([{"name": "white"}, {"name": "placement_3x", "placement": 3.0},
                             {"name": "gm_mix", "gauss_markov": [[1.0, 3.0], [1.0, 30.0], [1.0, 300.0]]}], SESSION)


def _data(truth, size, rep, profile, seed=5):
    rec, key = B.simulate_case(truth, size, rep, seed=seed, session=SESSION, rules=RULES, profile=profile)
    return pose_data_from_static(detect_static_recording(rec), SESSION.g), key


@pytest.mark.parametrize("name, corr", [("placement_3x", 0.0), ("placement_3x", 0.6), ("gm_mix", 0.0)])
def test_the_oracle_covariance_is_the_residuals_covariance(name, corr):
    """Under the profile's covariance of the detected poses (through the base fit's gradients,
    the cross-axis terms of a correlated profile included), the base model's GLS chi-square
    has its expectation n - 9 (100 effect-free sessions: the mean within 4 of its standard
    errors; the same covariance without the offset gives a mean of 231 on 21).  The mean does
    not see the cross-axis terms (they average out over pose directions): the correlated case
    checks that they do not break it."""
    prof = PROFILES[name]
    if corr:
        prof = P.NoiseProfile(prof.name, prof.white, prof.components, placement=prof.placement, axis_correlation=corr)
    chi2, dof = [], None
    for rep in range(100):
        data, _ = _data(B.NONE, 0.0, rep, prof)
        base = fit(data)
        dur = data.t_end - data.t_start + 1.0 / SESSION.rate
        w = -(base.J[:, :3] * base.sigma[:, None])
        S_ = P.pose_residual_covariance(prof, data.t_start, dur, np.round(dur * SESSION.rate), SESSION.rate, w)
        X = base.J * base.sigma[:, None]
        L = np.linalg.inv(np.linalg.cholesky(S_))
        Q, _ = np.linalg.qr(L @ X)
        e = L @ base.residuals
        e = e - Q @ (Q.T @ e)
        chi2.append(float(e @ e))
        dof = len(data) - 9
    se = np.sqrt(2 * dof / len(chi2))
    assert abs(np.mean(chi2) - dof) < 4 * se, (np.mean(chi2), dof)


def test_the_oracle_names_what_is_planted_and_little_else():
    """White noise: a quadratic at 4 oracle MDE is named, a pose shifted by 4 of its MDE is
    named at its index; 40 effect-free sessions: at most 5 named anything (one-sided
    binomial bound, 5 %)."""
    rng = np.random.default_rng(0)
    data, _ = _data("quadratic", 4.0, 0, PROFILES["white"])
    row = oracle_detection(data, PROFILES["white"], SESSION.rate, RULES, rng)
    assert row["null"] == "oracle" and row["effects"].split("+")[0] == "quadratic", row
    data, key = _data(B.OUTLIER, 4.0, 1, PROFILES["white"])
    row = oracle_detection(data, PROFILES["white"], SESSION.rate, RULES, rng)
    assert f"outlier_pose@{key['outlier_pose']}" in row["named_set"].split("+"), (row, key["outlier_pose"])
    named = 0
    for rep in range(40):
        data, _ = _data(B.NONE, 0.0, 100 + rep, PROFILES["white"])
        named += oracle_detection(data, PROFILES["white"], SESSION.rate, RULES, rng)["named_set"] != ""
    assert named <= 5, named
    assert stats.binom.sf(5, 40, 0.05) < 0.05


def test_the_placement_profile_offsets_every_pose_alone():
    prof = PROFILES["placement_3x"]
    starts = np.array([0, 10, 25, 40])
    x = P.placement_offsets(prof, np.random.default_rng(0), starts, 60)
    assert np.all(x[:10] == x[0]) and np.all(x[10:25] == x[10]) and not np.allclose(x[0], x[10])
    assert np.allclose(P.placement_offsets(PROFILES["white"], np.random.default_rng(0), starts, 60), 0.0)
    assert P.NoiseProfile.from_dict(prof.to_dict()) == prof
    assert prof.placement[0] == pytest.approx(3.0 * P.pose_mean_white(SESSION))


def test_agreement_with_the_oracle_is_scored_per_recording():
    keys = pd.DataFrame([{"recording": r, "profile": "p", "truth": t, "expected": t, "effects_injected": e,
                          "size_mde": 3.0, "replicate": 0, "noise_window": -1, "outlier_t": np.nan}
                         for r, t, e in (("a", "quadratic", "quadratic"), ("b", B.NONE, ""), ("c", B.OUTLIER, ""))])
    dets = pd.DataFrame([
        {"recording": "a", "null": "wander", "outcome": "quadratic", "effects": "quadratic",
         "named_set": named_set(["quadratic"], [])},
        {"recording": "a", "null": "oracle", "outcome": "quadratic", "effects": "quadratic", "named_set": "quadratic"},
        {"recording": "b", "null": "wander", "outcome": B.OUTLIER, "effects": B.OUTLIER,
         "named_set": named_set([B.OUTLIER], [4])},
        {"recording": "b", "null": "oracle", "outcome": "none", "effects": "", "named_set": ""},
        {"recording": "c", "null": "wander", "outcome": B.OUTLIER, "effects": B.OUTLIER,
         "named_set": named_set([B.OUTLIER], [7])},
        {"recording": "c", "null": "oracle", "outcome": B.OUTLIER, "effects": B.OUTLIER,
         "named_set": named_set([B.OUTLIER], [8])},
    ])
    sc = S.score_cases(keys, dets)
    col = sc[sc.null == "wander"].set_index("recording")
    assert col.loc["a", "agrees_with_oracle"] and not col.loc["b", "agrees_with_oracle"]
    assert not col.loc["c", "agrees_with_oracle"]                       # another pose
    assert col.loc["b", "outlier_false"] and col.loc["b", "false_positive"]
    diff = S.oracle_differences(sc).set_index("truth")
    assert diff.loc[B.NONE, "loop_only"] == "outlier_pose: 1" and diff.loc[B.NONE, "oracle_only"] == ""
    assert diff.loc[B.OUTLIER, "loop_only"] == "outlier_pose: 1" and diff.loc[B.OUTLIER, "oracle_only"] == "outlier_pose: 1"
    summ = S.summary(sc, S.rates(sc), alpha=0.05, power=0.8)
    ag = summ[(summ.null == "wander") & (summ.metric == "oracle_agreement")].iloc[0]
    assert ag.value == pytest.approx(1 / 3) and ag.n == 3
