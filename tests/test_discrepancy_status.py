"""What a user reads in the discrepancy report: one status, one meaning; the noise between poses in words;
the per-placement offset; the outlier family's exact null.

Sessions are simulated at the pose level as in tests/test_discrepancy_wander.py (30 poses of
5.5 s, 16-bit counts), with fixed seeds.
"""

import json

import numpy as np
import pytest
from scipy import stats

from accelcal.discrepancy import wander as C
from accelcal.discrepancy.detect import discrepancy
from accelcal.discrepancy.fit import forward, pose_data
from accelcal.discrepancy.wander_model import describe_noise_model
from accelcal.discrepancy.schema import REPORT_SCHEMA, STATUS, check_statuses, upgraded_report
from accelcal.discrepancy.rules import Rules
from accelcal.errors import AccelcalError
from accelcal.jsonsafe import json_safe
from accelcal.model import m_from_params
from accelcal.simulation import random_directions

G = 9.80665
RATE, N_SAMPLE = 100.0, 3.3
FAST = Rules(n_boot=199, candidates=("quadratic", "cubic", "bias_drift"))


def _session(rng, n=30, wander=None, placement=0.0, rest=None):
    """Pose data: white pose noise of each rest (rests of ``rest`` s, default 5.5 s), plus a
    wander (interval means) or a per-placement offset of ``placement`` counts per axis."""
    T = np.full(n, 5.5) if rest is None else np.asarray(rest, float)
    a = np.concatenate([[0.0], np.cumsum(T[:-1] + 2.0)])
    u = random_directions(rng, n)
    M, b = m_from_params(np.full(3, 414.0), np.deg2rad([0.4, -0.7, 1.0])), np.array([32768.0, 32500.0, 33000.0])
    ms = np.repeat((N_SAMPLE / np.sqrt(T * RATE))[:, None], 3, axis=1)
    z = forward(G * u, M, b, {}) + ms * rng.standard_normal((n, 3)) + placement * rng.standard_normal((n, 3))
    if wander:
        z = z + C.simulate_interval_means(rng, wander, a, T)
    return pose_data(z, G, ms, a + T / 2, t_start=a, t_end=a + T)


def _json(result) -> dict:
    return json.loads(json.dumps(json_safe(result.to_dict())))


def test_the_two_readings_of_the_excess_differ_and_say_so():
    """A session with a slow wander and no effect: against the rests' white noise the excess
    stays (nothing to name), so ``excess_status_white`` is ``not explained``; the model the
    loop used (the wander estimated jointly) predicts it: ``excess_status`` is ``explained``,
    carried by the bias wander.  Both values are in the schema."""
    rng = np.random.default_rng(3)
    pose_white = N_SAMPLE / np.sqrt(5.5 * RATE)
    res = discrepancy(_session(rng, wander={"gauss_markov": [(6 * pose_white, 120.0)]}), FAST)
    out = _json(res)
    assert out["effects"] == [] and out["noise_model"]["term"] == "bias_wander"
    assert out["excess_status_white"] == "not explained"
    assert out["excess_status"] == "explained" and "bias_wander" in out["excess_explained_by"]
    assert out["excess_explained"] is True
    assert check_statuses(out)["excess_status"] == "explained"
    white = _json(discrepancy(_session(np.random.default_rng(3), wander={"gauss_markov": [(6 * pose_white, 120.0)]}),
                              Rules(null="white", candidates=FAST.candidates)))
    assert white["excess_status"] == white["excess_status_white"]  # one model: one reading


def test_an_undefined_status_value_is_refused():
    with pytest.raises(AccelcalError, match="excess_status"):
        check_statuses({"outcome": "none", "excess_status": "mostly explained", "excess_status_white": "explained"})
    assert set(REPORT_SCHEMA["properties"]["excess_status"]["enum"]) == set(STATUS["excess_status"])
    assert {"no excess", "explained", "not explained", "untestable"} == set(STATUS["excess_status_white"])


def test_the_earlier_name_of_the_wander_null_is_still_read():
    """The time-correlated noise model has one name, ``wander``; a config or report of an
    earlier version (``colored`` null, ``gap_colored_*`` keys) still reads, as the new names.
    An unknown null is still refused."""
    assert Rules(null="colored").null == "wander" == Rules.from_config({None: "colored"}).null
    old = {"outcome": "none", "null": "colored", "gap_colored_before": 2.0, "gap_colored_after": 1.5,
           "excess_status": "explained", "excess_status_white": "not explained", "rules": {"null": "colored"}}
    assert check_statuses(old)["null"] == "wander"
    new = upgraded_report(old)
    assert (new["gap_wander_before"], new["gap_wander_after"]) == (2.0, 1.5) and "gap_colored_after" not in new
    assert new["rules"]["null"] == "wander" and old["null"] == "colored"  # a copy
    with pytest.raises(AccelcalError, match="null must be one of"):
        Rules(null="pink")
    with pytest.raises(AccelcalError, match="report status null"):
        check_statuses({**old, "null": "pink"})


def test_a_per_placement_offset_is_named_as_such():
    """Offsets independent from pose to pose, 8x the pose noise, on rests of different
    lengths (so the offset does not follow each pose's own noise as a white scale would):
    the noise model names a per-placement offset of about the planted size, and the excess
    is explained by it; the reading says what separates it from an effect of the
    orientation on these poses."""
    rng = np.random.default_rng(5)
    rest = rng.uniform(3.0, 20.0, 30)
    size = 8 * N_SAMPLE / np.sqrt(5.5 * RATE)
    res = discrepancy(_session(rng, placement=size, rest=rest), FAST)
    nm = _json(res)["noise_model"]
    assert nm["term"] == "per_placement_offset" and nm["process"] == "per_placement"
    assert nm["size_ci"][0] < size < nm["size_ci"][1]
    assert nm["placement"]["reading"] in nm["reading"]
    assert res.statistics()["excess_status"] == "explained"
    assert "per_placement_offset" in res.statistics()["excess_explained_by"]


@pytest.mark.parametrize("repeats_follow_the_orientation", [False, True])
def test_repeated_placements_tell_an_offset_from_an_orientation_effect(repeats_follow_the_orientation):
    """Six orientations placed twice, far apart in the session, with offsets of 8 pose sigmas:
    independent offsets scatter between the two placements as the offset model says (the
    pure-error chi-square is not small); offsets that belong to the orientation (the second
    placement repeats the first's) agree far better than independent ones would."""
    from accelcal.discrepancy.fit import fit
    from accelcal.discrepancy.wander_model import repeated_placements

    rng = np.random.default_rng(21)
    n = 36
    u = random_directions(rng, n)
    u[30:] = u[[2, 7, 11, 16, 20, 25]]          # six orientations placed again, late in the session
    T = np.full(n, 5.5)
    a = np.concatenate([[0.0], np.cumsum(T[:-1] + 2.0)])
    M, b = m_from_params(np.full(3, 414.0), np.deg2rad([0.4, -0.7, 1.0])), np.array([32768.0, 32500.0, 33000.0])
    ms = np.full((n, 3), N_SAMPLE / np.sqrt(5.5 * RATE))
    offsets = 8 * ms * rng.standard_normal((n, 3))
    if repeats_follow_the_orientation:
        offsets[30:] = offsets[[2, 7, 11, 16, 20, 25]]
    z = forward(G * u, M, b, {}) + ms * rng.standard_normal((n, 3)) + offsets
    data = pose_data(z, G, ms, a + T / 2, t_start=a, t_end=a + T)
    res = discrepancy(data, FAST)
    assert res.noise_model["term"] == "per_placement_offset"
    pl = res.noise_model["placement"]
    assert pl["pure_error_dof"] == 6 and sorted(map(sorted, pl["groups"])) == [[2, 30], [7, 31], [11, 32], [16, 33],
                                                                                [20, 34], [25, 35]]
    if repeats_follow_the_orientation:
        assert pl["p_lower"] < 0.01 and "belongs to the orientation" in pl["reading"]
    else:
        assert pl["p_lower"] > 0.05 and "scatter as independent offsets do" in pl["reading"]
    assert repeated_placements(data, fit(data), None)["pure_error_dof"] == 6


def test_a_random_walk_is_read_as_one():
    """The reading of a random walk never prints an infinite size or time: it says there is
    none and gives its coefficient and its change over the session."""
    nm = {"estimated": True, "term": "bias_wander", "process": "random_walk", "size": None, "size_ci": [0.00048, None],
          "tau_s": None, "tau_ci": [12.0, None], "random_walk_K": 4.2e-5, "random_walk_K_ci": [1e-5, 9e-5],
          "change_over_session": 4.2e-5 * np.sqrt(600.0), "session_s": 600.0, "white_scale": 0.9,
          "white_scale_ci": [0.6, 1.3], "axis_correlation": 0.0, "axis_correlation_ci": [0.0, 0.33]}
    text = describe_noise_model(nm, "m/s^2")
    assert "inf" not in text and "random walk" in text and "no stationary size" in text
    assert "K 4.2e-05 m/s^2/sqrt(s)" in text and "over the 600 s session" in text
    gm = {**nm, "process": "gauss_markov", "size": 0.001, "size_ci": [0.0005, None], "tau_s": 2.8,
          "tau_ci": [1.0, None], "time_correlation_established": False}
    text = describe_noise_model(gm, "m/s^2")
    assert "no upper bound: a random walk is not ruled out" in text and "inf" not in text
    assert "time correlation is not established" in text


def test_the_json_of_a_random_walk_has_no_infinite_numbers_unexplained():
    rng = np.random.default_rng(9)
    pose_white = N_SAMPLE / np.sqrt(5.5 * RATE)
    res = discrepancy(_session(rng, wander={"random_walk": 4 * pose_white / np.sqrt(200.0)}), FAST)
    nm = _json(res)["noise_model"]
    assert nm["process"] == "random_walk", nm["process"]  # a fixed draw whose planted walk REML names
    assert nm["size"] is None and "no stationary size" in nm["reading"] and "null for a random walk" in nm["unit"]
    assert np.isfinite(nm["change_over_session"]) and nm["change_over_session"] > 0


def test_the_outlier_null_is_the_exact_distribution_of_the_largest_residual():
    """Independent poses (b̂ the unit vectors of R^r, known variance): P(max |z_i| >= c) =
    1 - (1 - 2 Φ(-c))^r exactly; the Monte Carlo p-value is within its binomial error."""
    r = 20
    bhat = np.eye(r)
    for c in (2.5, 3.2):
        exact = 1 - (1 - 2 * stats.norm.sf(c)) ** r
        p, n = C.max_null_pvalue(bhat, c, np.random.default_rng(1), alpha=0.05, family=1, studentised=False,
                                 stop_early=False)
        assert n == C.outliers.MAX_DRAWS
        assert abs(p - exact) < 4 * np.sqrt(exact * (1 - exact) / n), (c, p, exact)
    # a p-value far above alpha stops early; one far below its Holm level too
    _, n_hi = C.max_null_pvalue(bhat, 1.0, np.random.default_rng(2), alpha=0.05, family=7, studentised=False)
    _, n_lo = C.max_null_pvalue(bhat, 6.0, np.random.default_rng(2), alpha=0.05, family=7, studentised=False)
    assert n_hi == C.outliers.FIRST_BATCH and n_lo <= C.outliers.FIRST_BATCH + 2 * C.outliers.DRAW_BATCH


def test_the_outlier_family_is_calibrated_under_a_wander():
    """Effect-free sessions with a Gauss-Markov wander (3 pose sigmas, τ = 30 s): the outlier
    family's p-value (largest studentised residual against its exact null under the fitted
    wander) falls below α in at most its share of the sessions (one-sided binomial bound at
    5 % over 60 sessions: 7 of 60 would fail)."""
    rng = np.random.default_rng(11)
    pose_white = N_SAMPLE / np.sqrt(5.5 * RATE)
    rules = Rules(n_boot=199, candidates=("quadratic",), max_rounds=1, max_outliers=1)
    hits = 0
    for _ in range(60):
        res = discrepancy(_session(rng, wander={"gauss_markov": [(3 * pose_white, 30.0)]}), rules)
        hits += res.outlier_tests[0].p_value <= 0.05
    assert hits <= 6, hits
    assert stats.binom.sf(6, 60, 0.05) < 0.13
