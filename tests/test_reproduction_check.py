"""The CI reproduction check: a ledger against its expected verdicts."""

import pandas as pd

from accelcal_repro.claims import COLUMNS, expected_verdicts, verdict_changes


def ledger(*rows):
    return pd.DataFrame([dict(zip(COLUMNS, (p, c, "text", "pv", "rv", v, "ev"))) for p, c, v in rows])


def test_equal_ledgers_have_no_changes():
    led = ledger(("tereshkov", "a", "reproduced"), ("batista2011", "b", "not_reproduced"))
    assert verdict_changes(led, expected_verdicts(led)) == []


def test_a_changed_verdict_is_named():
    old = ledger(("tereshkov", "a", "reproduced"), ("batista2011", "b", "not_reproduced"))
    new = ledger(("tereshkov", "a", "not_reproduced"), ("batista2011", "b", "not_reproduced"))
    assert verdict_changes(new, expected_verdicts(old)) == [
        "tereshkov/a: verdict changed from reproduced to not_reproduced"]


def test_new_and_vanished_claims_are_named():
    old = ledger(("tereshkov", "a", "reproduced"))
    new = ledger(("tereshkov", "b", "reproduced"))
    changes = verdict_changes(new, expected_verdicts(old))
    assert changes == ["tereshkov/a: expected verdict reproduced but the ledger has no such claim",
                       "tereshkov/b: new claim (verdict reproduced) has no expected verdict"]


def test_expected_verdicts_are_sorted_and_minimal():
    led = ledger(("tereshkov", "b", "reproduced"), ("batista2011", "z", "not_reproducible"),
                 ("tereshkov", "a", "not_reproduced"))
    exp = expected_verdicts(led)
    assert list(exp.columns) == ["paper", "claim_id", "verdict"]
    assert list(exp["claim_id"]) == ["z", "a", "b"]
