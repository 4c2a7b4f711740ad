"""adis_real is out of the oracle-agreement goal (issue 34 item 3): its "oracle" is a fitted model.

Fails if a real-record profile's agreement is judged against the 0.95 goal, or if the
claim counts it.
"""

import pandas as pd

from accelcal_repro.discrepancy.claims import _oracle_row
from accelcal_repro.discrepancy.scoring import ORACLE, REFERENCE, _oracle_and_outlier_rows


def _scores(kind, agree):
    n = len(agree)
    return pd.DataFrame({"null": "wander", "profile": "p", "profile_kind": kind, "truth": "none", "size_mde": 0.0,
                         "noise_window": range(n), "agrees_with_oracle": agree, "oracle_named_set": [""] * n,
                         "outlier_false": [False] * n, "outlier_located": [False] * n})


def test_real_profile_agreement_is_a_reference_not_the_goal():
    real = [r for r in _oracle_and_outlier_rows("wander", "adis_real", _scores("real", [True] * 50 + [False] * 50))
            if r["metric"] == "oracle_agreement"][0]
    sim = [r for r in _oracle_and_outlier_rows("wander", "adis_model", _scores("fitted", [True] * 50 + [False] * 50))
           if r["metric"] == "oracle_agreement"][0]
    assert real["verdict"] == REFERENCE and "not part of the oracle goal" in real["rule"]
    assert sim["verdict"] == "fail" and real["value"] == sim["value"] == 0.5
    assert ORACLE == "oracle"


def test_the_claim_counts_only_profiles_with_an_oracle():
    rows = pd.DataFrame([
        {"null": "wander", "metric": "oracle_agreement", "profile": "adis_model", "effect": "all", "value": 0.99,
         "ci_low": 0.97, "ci_high": 1.0, "n": 300, "n_independent": 300, "verdict": "pass"},
        {"null": "wander", "metric": "oracle_agreement", "profile": "adis_real", "effect": "all", "value": 0.5,
         "ci_low": 0.4, "ci_high": 0.6, "n": 300, "n_independent": 300, "verdict": REFERENCE}])
    row = _oracle_row(rows, ["wander"])
    assert "adis_real" not in row["evidence"] and "1/1 testable" in row["evidence"], row
