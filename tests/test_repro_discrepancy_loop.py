"""The discrepancy loop on sessions simulated by the reproductions' benchmark (accelcal_repro.discrepancy.benchmark): effects named, none on effect-free sessions, the gap closed.

Moved from tests/test_discrepancy_loop.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

import numpy as np
import pytest
from accelcal_repro.discrepancy import benchmark as B
from accelcal.discrepancy.detect import discrepancy
from accelcal.effects import EFFECT_IDS
from tests.test_discrepancy_loop import NULL_RULES, RULES


SESSION = B.Session()


def _run(truth, size, rep, seed=20240707, rules=RULES):
    rec, key = B.simulate_case(truth, size, rep, seed=seed, session=SESSION, rules=rules)
    return B.detect_case(rec, SESSION.g, rules), key


@pytest.mark.parametrize("null", sorted(NULL_RULES))
@pytest.mark.parametrize("eid", EFFECT_IDS)
def test_names_each_injected_effect(eid, null):
    for rep in range(2):
        row, key = _run(eid, 4.0, rep, rules=NULL_RULES[null])
        assert row["outcome"] == eid, (rep, row)
        # the estimate is the injected parameter within a few standard errors
        est = np.array([row[f"estimate_{a}"] for a in B.suffixes(eid)])
        se = np.array([row[f"se_{a}"] for a in B.suffixes(eid)])
        true = np.array([key[f"param_{a}"] for a in B.suffixes(eid)])
        assert np.all(np.abs(est - true) < 5 * se), (est, true, se)


@pytest.mark.parametrize("null", sorted(NULL_RULES))
def test_names_none_on_effect_free_recordings(null):
    outcomes = [_run(B.NONE, 0.0, rep, rules=NULL_RULES[null])[0]["outcome"] for rep in range(4)]
    assert outcomes == ["none"] * 4


@pytest.mark.parametrize("null", sorted(NULL_RULES))
def test_refuses_the_constant_temperature(null):
    row, key = _run(B.CONSTANT_TEMPERATURE, 3.0, 0, rules=NULL_RULES[null])
    assert key["temp_range"] == 0.0
    assert row["outcome"] == B.NOT_IDENTIFIABLE
    assert row["identifiable_temperature"] is False and row["identifiable_temperature_scale"] is False
    assert set(row["not_identifiable"].split("+")) == {"temperature", "temperature_scale"}


@pytest.mark.parametrize("null", sorted(NULL_RULES))
def test_gap_shrinks_to_the_noise_after_the_refit(null):
    from accelcal.static import detect_static_recording
    from accelcal.discrepancy.fit import pose_data_from_static

    rules = NULL_RULES[null]
    rec, _ = B.simulate_case("quadratic", 4.0, 0, seed=20240707, session=SESSION, rules=RULES)
    res = discrepancy(pose_data_from_static(detect_static_recording(rec), SESSION.g), rules)
    s = res.statistics()
    assert res.effects[0] == "quadratic"
    # before: far beyond what noise explains (χ² upper tail); after: consistent with it
    assert s["chi2_p_before"] < 1e-6 and s["gap_before"] > 1.5 * s["gap_expected_before"]
    assert s["chi2_p_after"] > 0.01 and s["gap_after"] < s["gap_before"] / 1.5
    assert s["gap_lopo_after"] < s["gap_lopo_before"]  # out of sample too
    assert s["excess_status"] == "explained"
    # effect-free: the base model is already at the noise level
    rec0, _ = B.simulate_case(B.NONE, 0.0, 1, seed=20240707, session=SESSION, rules=RULES)
    s0 = discrepancy(pose_data_from_static(detect_static_recording(rec0), SESSION.g), rules).statistics()
    assert s0["excess_status"] == "no excess" and s0["gap_after"] == s0["gap_before"]
