"""The CI reproduction check: a ledger against its expected verdicts."""

from pathlib import Path

import pandas as pd

from accelcal_repro.claims import (COLUMNS, EXPECTED_COLUMNS, NOT_TESTABLE, VERDICTS, expected_verdicts,
                                   verdict_changes)


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


def test_not_testable_is_a_verdict_of_its_own():
    """A claim the CI scale cannot decide is expected as such; becoming testable (or the
    reverse) is a change the check names, in both directions."""
    led = ledger(("discrepancy", "a", NOT_TESTABLE), ("tereshkov", "b", "reproduced"))
    exp = expected_verdicts(led)
    assert list(exp["verdict"]) == [NOT_TESTABLE, "reproduced"]
    assert verdict_changes(led, exp) == []
    now = ledger(("discrepancy", "a", "reproduced"), ("tereshkov", "b", NOT_TESTABLE))
    assert verdict_changes(now, exp) == [f"discrepancy/a: verdict changed from {NOT_TESTABLE} to reproduced",
                                         f"tereshkov/b: verdict changed from reproduced to {NOT_TESTABLE}"]


def test_the_expected_ci_verdicts_file_is_valid():
    """tests/expected_verdicts.ci.csv: sorted, one row per claim, every verdict a ledger verdict."""
    path = Path(__file__).with_name("expected_verdicts.ci.csv")
    exp = pd.read_csv(path, dtype=str, keep_default_na=False)
    assert list(exp.columns) == list(EXPECTED_COLUMNS)
    assert set(exp["verdict"]) <= set(VERDICTS)
    assert not exp.duplicated(["paper", "claim_id"]).any()
    assert exp.equals(exp.sort_values(["paper", "claim_id"]).reset_index(drop=True))
