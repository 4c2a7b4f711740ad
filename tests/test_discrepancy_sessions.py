"""The real-session study: a re-simulation reproduces a session whose noise it knows and misses one
whose wander it is not told about; the stability test flags a parameter that moved."""

import numpy as np
import pandas as pd
import pytest

from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.report import discrepancy_report
from accelcal_repro.discrepancy import benchmark as B
from accelcal_repro.discrepancy import profiles as P
from accelcal_repro.discrepancy import sessions as SS

SESSION = B.Session()
WHITE_RULES = B.rules_with_null(Rules(), "white")


def _report(profile, seed=3):
    rec, _ = B.simulate_case(B.NONE, 0.0, seed, seed=7, session=SESSION, rules=WHITE_RULES, profile=profile)
    rep = discrepancy_report(rec, SESSION.g, rules=WHITE_RULES, stochastic=None).to_dict()
    rep["g"] = SESSION.g
    return rec, rep


def test_resimulating_a_white_session_reproduces_its_residuals():
    rec, rep = _report(P.NoiseProfile("white", (SESSION.noise_counts,) * 3))
    sims = SS.resimulate(rec, rep, n_rep=12, seed=1)
    assert (sims[sims.pose < 0].z == 0).all()  # no replicate failed
    gaps = pd.DataFrame(SS.gap_rows("w", rep, sims)).set_index("model")
    # the measured excess lies inside the re-simulated distribution
    assert gaps.loc["before", "excess_sim_q025"] <= gaps.loc["before", "excess_measured"] \
        <= gaps.loc["before", "excess_sim_q975"] * 1.1
    assert gaps.loc["before", "rms_ratio"] == pytest.approx(1.0, abs=0.4)


def test_a_named_wander_closes_the_gap_the_white_simulator_leaves():
    gm = P.NoiseProfile("gm", (SESSION.noise_counts,) * 3, (("gauss_markov", ((0.6, 30.0),) * 3),))
    rec, rep = _report(gm, seed=5)
    before_only = SS.gap_rows("gm", rep, SS.resimulate(rec, rep, n_rep=12, seed=1))
    rep["noise_model"] = {"estimated": True, "term": "bias_wander", "process": "gauss_markov", "size": 0.6,
                          "tau_s": 30.0}
    gaps = pd.DataFrame(SS.gap_rows("gm", rep, SS.resimulate(rec, rep, n_rep=12, seed=1))).set_index("model")
    assert before_only[0]["excess_measured"] > 1.5  # the wander shows as excess over the white yardstick
    assert gaps.loc["before", "excess_sim_q975"] < gaps.loc["before", "excess_measured"]  # white cannot make it
    assert gaps.loc["after", "rms_ratio"] < gaps.loc["before", "rms_ratio"]
    assert gaps.loc["after", "excess_sim_q025"] <= gaps.loc["after", "excess_measured"] \
        <= gaps.loc["after", "excess_sim_q975"] * 1.1


def test_a_named_flicker_wander_is_resimulated_as_flicker():
    """The loop's flicker member (size = the noise library's B) is re-simulated as that term, with
    a tau-less row; a KeyError/TypeError on tau_s here once stopped every measured session."""
    fl = P.NoiseProfile("fl", (SESSION.noise_counts,) * 3, (("bias_instability", (0.8,) * 3),))
    rec, rep = _report(fl, seed=5)
    rep["noise_model"] = {"estimated": True, "term": "bias_wander", "process": "flicker", "size": 0.8, "tau_s": None}
    assert P.wander_components(rep) == (("bias_instability", (0.8, 0.8, 0.8)),)
    gaps = pd.DataFrame(SS.gap_rows("fl", rep, SS.resimulate(rec, rep, n_rep=12, seed=1))).set_index("model")
    assert gaps.loc["after", "rms_ratio"] < gaps.loc["before", "rms_ratio"]
    assert P.joint_source({**rep, "rate": 100.0}, "fl")["models"][0]["bias_instability"] == 0.8


def test_stability_flags_the_parameter_that_moved():
    rng = np.random.default_rng(0)
    rows = []
    for k in range(3):
        for par, moved in (("s_x", 0.0), ("b_x", 5e-3 * k)):
            rows.append({"recording": f"r{k}", "parameter": par, "value": 1e-3 * rng.standard_normal() + moved,
                         "se": 1e-3})
    st = SS.stability_rows(pd.DataFrame(rows), alpha=0.05).set_index("parameter")
    assert bool(st.loc["s_x", "stable"]) and not bool(st.loc["b_x", "stable"])
    assert st.loc["b_x", "p_adjusted"] < 1e-6 and st.loc["b_x", "dof"] == 2


def test_diagnostics_tell_pose_offsets_from_noise():
    """Residuals that are a property of the pose (an offset held through the whole rest) agree
    between the two halves of each rest; residuals of white noise do not."""
    import dataclasses

    rec, rep = _report(P.NoiseProfile("white", (SESSION.noise_counts,) * 3))
    white = SS.diagnostics_row("w", rec, rep)
    assert abs(white["half_consistency"]) < 0.5 and white["within_pose_drift"] == pytest.approx(1.0, abs=0.35)
    ranges = SS._rest_ranges(rec, rep)
    acc = np.array(rec.acc, float)
    rng = np.random.default_rng(4)
    for a, b in ranges:
        acc[a:b] += rng.normal(0.0, 1.0, 3)  # a per-pose offset of several pose-mean standard errors
    shifted = dataclasses.replace(rec, acc=acc)
    rep2 = discrepancy_report(shifted, SESSION.g, rules=WHITE_RULES, stochastic=None).to_dict()
    rep2["g"] = SESSION.g
    d = SS.diagnostics_row("o", shifted, rep2)
    assert d["half_consistency"] > 0.9 and d["within_pose_drift"] < 1.5


def test_a_six_pose_session_says_what_cannot_be_tested():
    rec, _ = _report(P.NoiseProfile("white", (SESSION.noise_counts,) * 3))
    from accelcal.discrepancy.report import StochasticSettings

    summary = pd.DataFrame([{"recording": "six", "estimator": "bias_lls", "n_poses": 6, "excess": 40.0,
                             "reduced_chi2": 1600.0, "dof": 3}])
    named, excess = SS.few_poses_rows("six", rec, summary, StochasticSettings(n_boot=19, n_resim=1))
    kinds = {r["item"]: r["kind"] for r in named}
    assert all(kinds[k] == "not_testable" for k in SS.FEW_POSES_LIMITS)
    assert excess[0]["excess_observed"] == 40.0 and "3 dof" in excess[0]["excess_status"]
