"""Tereshkov Monte Carlo and claims: observability in straight vs turning motion,
convergence times of the right order, and claim checks that reject a broken estimator."""

import numpy as np
import pandas as pd
import pytest

from accelcal_repro.claims import COLUMNS
from accelcal.tereshkov import estimator
from accelcal_repro.tereshkov import montecarlo as mc
from accelcal_repro.tereshkov.claims import tereshkov_claims
from accelcal_repro.tereshkov.montecarlo import convergence_time

CFG = {
    "seed": 11,
    "imu": {"rate_hz": 20},
    "gnss": {"rate_hz": 10},
    # turn-heavy field paths so that a short run shows both convergences
    "vehicle": {"straight_s": [25, 45], "turn_deg": [270, 360], "turn_rate_dps": [8, 10]},
    "monte_carlo": {"duration_s": 700, "table_every_s": 2, "steady_state_from_s": 450},
    "scenarios": {"field": {"runs": 3}, "straight": {"runs": 2},
                  "observability": {"runs": 2, "duration_s": 240},
                  "artificial": {"runs": 2}},
    "sweep": {"runs": 1, "duration_s": 700, "steady_state_from_s": 450, "angles_deg": [0, 15], "kinds": ["roll_pitch"]},
}
SS = CFG["monte_carlo"]["steady_state_from_s"]


@pytest.fixture(scope="module")
def tables():
    # one estimator loop for all four scenarios (same duration)
    out = mc.run_scenarios(CFG, ["field", "straight", "artificial", "sweep"])
    field, straight, art, sweep = (out[k][0] for k in ("field", "straight", "artificial", "sweep"))
    summary = mc.convergence_summary(pd.concat([field, straight]), SS)
    obs, _ = mc.observability_table(CFG)
    return {"field": field, "straight": straight, "artificial": art, "sweep_table": sweep, "timing": out,
            "summary": summary, "obs": obs,
            "art": mc.artificial_summary(art, SS), "sweep": mc.sweep_summary(sweep, SS)}


def _get(summary, scenario, sensor, col):
    return float(summary[(summary["scenario"] == scenario) & (summary["sensor"] == sensor)][col].iloc[0])


def test_tidy_table_shape(tables):
    f = tables["field"]
    assert set(f["sensor"]) == {"gyro", "accel", "attitude"}
    assert set(f["axis"]) == {"x", "y"}
    assert f.groupby(["sensor", "axis"]).size().nunique() == 1
    assert np.isfinite(f[["estimate", "truth", "error"]].to_numpy()).all()


def test_accel_converges_with_turns_not_straight(tables):
    s = tables["summary"]
    assert _get(s, "field", "accel", "final_ratio") < 0.2
    assert _get(s, "straight", "accel", "final_ratio") > 0.8
    # gyro converges either way
    assert _get(s, "straight", "gyro", "final_ratio") < 0.2
    assert _get(s, "field", "gyro", "final_ratio") < 0.2


def test_torque_ignores_accel_bias_in_straight_motion(tables):
    o = tables["obs"].groupby("mode")["sensitivity"].mean()
    assert o["straight"] < 0.1 * o["turn"]
    t = tables["obs"][tables["obs"]["mode"] == "turn"]
    np.testing.assert_allclose(t["du_rms_dps"], t["predicted_rms_dps"], rtol=0.1)


def test_convergence_times_of_the_right_order(tables):
    s = tables["summary"]
    tg, ta = _get(s, "field", "gyro", "t_conv"), _get(s, "field", "accel", "t_conv")
    # gyro: a 40 s filter updating part of the time: between one and ten time constants
    assert 40 <= tg <= 400
    assert 40 <= _get(s, "straight", "gyro", "t_conv") <= 250
    # accelerometer: slower, it only updates in settled turns
    assert ta > tg
    assert np.isnan(_get(s, "straight", "accel", "t_conv"))


def test_convergence_time_definition():
    t = np.arange(10.0)
    e = np.array([1.0, 0.5, 0.2, 0.04, 0.2, 0.05, 0.04, 0.05, 0.04, 0.05])
    # 5% of the excess over e_ss=0.045 is 0.048: first sample after which it always holds
    assert convergence_time(t, e, 0.045, 0.05) == 5.0
    assert np.isnan(convergence_time(t, np.r_[e[:-1], 0.5], 0.045, 0.05))


def test_claims_accept_the_estimator(tables):
    rows = tereshkov_claims(tables["summary"], tables["obs"], tables["art"], tables["sweep"])
    assert list(rows.columns) == list(COLUMNS)
    v = rows.set_index("claim_id")["verdict"]
    for cid in ("accel_unobservable_straight", "gyro_steady_state_rms", "accel_steady_state_rms",
                "artificial_bias_test", "installation_roll_pitch"):
        assert v[cid] == "reproduced", cid
    assert v["field_tests"] == "not_reproducible"


def _broken_eq14(u, rate_z, g, tau):
    """Deliberately wrong (14): a sign error (k = +k g/|g| instead of -k g/|g| in the
    inversion).  (A transposed matrix would not do: through the feedback it still
    converges, only more slowly, as long as its rotation error stays below 90°.)"""
    inv = 1.0 / rate_z
    return -g * np.stack([u[0] * inv - tau * u[1], tau * u[0] + u[1] * inv])


def test_claims_reject_a_broken_estimator(tables, monkeypatch):
    monkeypatch.setattr("accelcal.kernels._backend", "numpy")  # the broken formula is patched into the numpy loop
    monkeypatch.setattr(estimator, "_eq14", _broken_eq14)
    field, _ = mc.run_scenario(CFG, "field")
    summary = mc.convergence_summary(pd.concat([field, tables["straight"]]), SS)
    rows = tereshkov_claims(summary, tables["obs"], tables["art"], tables["sweep"]).set_index("claim_id")
    assert rows.loc["accel_steady_state_rms", "verdict"] == "not_reproduced"
    assert rows.loc["accel_unobservable_straight", "verdict"] == "not_reproduced"
    # the gyro rows do not depend on (14)
    assert rows.loc["gyro_steady_state_rms", "verdict"] == "reproduced"


def test_claims_reject_slow_gyro_filter(tables):
    s = tables["summary"].copy()
    sel = (s["scenario"] == "field") & (s["sensor"] == "gyro")
    s.loc[sel, "t_conv"] *= 10  # as a 400 s filter would give
    rows = tereshkov_claims(s, tables["obs"], tables["art"], tables["sweep"]).set_index("claim_id")
    assert rows.loc["gyro_convergence_time", "verdict"] == "not_reproduced"
    assert rows.loc["accel_slower_than_gyro", "verdict"] == "not_reproduced"


def test_jobs_merge_to_the_tables_of_one_job(tables):
    """Split over two jobs (run r in job r % 2), the merged tables equal one job's (to
    rounding: the batched matrix products differ in the last bit, ~1e-16, with the batch
    size); the wall times add up over the jobs."""
    parts = [mc.run_scenarios(CFG, ["field", "straight", "artificial", "sweep"], job=j, jobs=2) for j in (0, 1)]
    for name, whole in (("field", tables["field"]), ("artificial", tables["artificial"]),
                        ("sweep", tables["sweep_table"]), ("straight", tables["straight"])):
        assert set(parts[0][name][0]["run"]) == set(range(0, whole["run"].max() + 1, 2))
        merged = mc.merge_job_tables(p[name][0] for p in parts)
        assert list(merged.columns) == list(whole.columns)
        floats = list(whole.select_dtypes("float").columns)
        pd.testing.assert_frame_equal(merged.drop(columns=floats), whole.drop(columns=floats))
        np.testing.assert_allclose(merged[floats].to_numpy(), whole[floats].to_numpy(), rtol=1e-12, atol=1e-12,
                                   err_msg=name)
    timings = pd.DataFrame([p[n][1] for p in parts for n in ("field", "sweep")])
    merged = mc.merge_job_timings(timings).set_index("scenario")
    assert merged.loc["field", "runs"] == tables["timing"]["field"][1]["runs"] and merged.loc["field", "jobs"] == 2
    assert merged.loc["field", "estimator_s"] == pytest.approx(sum(p["field"][1]["estimator_s"] for p in parts))
    # a wrong merge (jobs concatenated in job order) is not the one-job table
    naive = pd.concat([p["field"][0] for p in parts], ignore_index=True).drop(columns="batch_row")
    assert not np.allclose(naive["estimate"], tables["field"]["estimate"])
    with pytest.raises(mc.InvalidParameterError, match="job 2 is not in 0 .. 1"):
        mc.job_share(mc.build_scenario(CFG, "field"), 2, 2)
