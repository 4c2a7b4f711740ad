"""The claims ledger: validation of rows and files, claim checks that can fail, and the least
sample a rule needs before its verdict can depend on the data.

The Burkhard (2024) claims are tested in tests/test_burkhard2024_checks.py; the minimum
sample of every stage's rules in tests/test_claims_scale.py."""

import math

import numpy as np
import pandas as pd
import pytest

from accelcal_repro.claims import (COLUMNS, NOT_TESTABLE, VERDICTS, Claim, LedgerError, MinimumSample,
                                   assemble_ledger, at_least, bootstrap_rule_minimum, lower_end_with_all_successes,
                                   power_rule_minimum, rank_rule_minimum, rate_lower_rule_minimum,
                                   rate_upper_rule_minimum, resolution_minimum, upper_end_with_no_success,
                                   validate_rows)
from accelcal_repro.discrepancy.scoring import clopper_pearson

CLAIM = Claim("burkhard2024", "demo", "A demo claim. Rule: reproduced if value >= 10", "≈35×")


def good_rows():
    return [CLAIM.judge(12.0, True, "table.csv: computed"),
            Claim("tereshkov", "gyro_converges", "Gyro bias converges in 120 s", "120 s").judge(
                130.0, False, "table.csv: computed"),
            Claim("batista2011", "no_data", "Something with private data", "x").not_reproducible("no public data")]


def write(tmp_path, name, rows):
    path = tmp_path / name
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_ledger_round_trip_keeps_rows_and_order(tmp_path):
    a = write(tmp_path, "a.csv", good_rows()[:2])
    b = write(tmp_path, "b.csv", good_rows()[2:])
    ledger = assemble_ledger([a, b])
    assert list(ledger.columns) == list(COLUMNS)
    assert ledger["claim_id"].tolist() == ["demo", "gyro_converges", "no_data"]
    assert ledger["verdict"].tolist() == ["reproduced", "not_reproduced", "not_reproducible"]
    assert ledger.loc[2, "reproduced_value"] == ""


@pytest.mark.parametrize("column,value,message", [
    ("paper", "nature2020", "unknown paper"),
    ("verdict", "maybe", "unknown verdict"),
    ("verdict", "", "unknown verdict"),
    ("claim", " ", "empty claim_id or claim text"),
    ("reproduced_value", "", "needs a reproduced_value"),
    ("evidence", "", "needs a reproduced_value and evidence"),
])
def test_bad_row_is_rejected_with_a_clear_message(tmp_path, column, value, message):
    rows = good_rows()
    rows[0][column] = value
    path = write(tmp_path, "bad.csv", rows)
    with pytest.raises(LedgerError, match=message) as e:
        assemble_ledger([path])
    assert "bad.csv" in str(e.value) and "\n" not in str(e.value)


def test_not_reproducible_needs_a_reason():
    rows = good_rows()
    rows[2]["evidence"] = ""
    with pytest.raises(LedgerError, match="needs the reason"):
        validate_rows(rows)


def test_missing_or_extra_columns_are_rejected(tmp_path):
    df = pd.DataFrame(good_rows()).drop(columns="evidence")
    with pytest.raises(LedgerError, match="missing \\['evidence'\\]"):
        assemble_ledger([write(tmp_path, "m.csv", df)])
    df = pd.DataFrame(good_rows()).assign(note="x")
    with pytest.raises(LedgerError, match="unexpected \\['note'\\]"):
        assemble_ledger([write(tmp_path, "e.csv", df)])


def test_duplicate_claim_ids_are_rejected_within_and_across_files(tmp_path):
    rows = good_rows()
    with pytest.raises(LedgerError, match="duplicate claim id.*burkhard2024/demo"):
        validate_rows(rows + [rows[0]])
    a, b = write(tmp_path, "a.csv", rows), write(tmp_path, "b.csv", rows[:1])
    with pytest.raises(LedgerError, match="duplicate claim id.*burkhard2024/demo"):
        assemble_ledger([a, b])
    # the same id for another paper is a different claim
    other = dict(rows[0], paper="batista2011")
    assert len(validate_rows(rows + [other])) == 4


def test_unreadable_file_and_bad_claim_definitions(tmp_path):
    with pytest.raises(LedgerError, match="cannot read"):
        assemble_ledger([tmp_path / "missing.csv"])
    with pytest.raises(LedgerError, match="unknown paper"):
        Claim("someone2020", "x", "text", "1")
    with pytest.raises(LedgerError, match="identifier"):
        Claim("burkhard2024", "has space", "text", "1")


def test_threshold_checks_can_fail():
    assert at_least(CLAIM, 35.0, 10.0, "t.csv").get("verdict") == "reproduced"
    assert at_least(CLAIM, 3.0, 10.0, "t.csv")["verdict"] == "not_reproduced"
    row = at_least(CLAIM, float("nan"), 10.0, "t.csv")
    assert row["verdict"] == "not_reproduced" and row["reproduced_value"] == "nan"


# ------------------------------------------------------------------ minimum samples
def test_not_testable_is_a_fourth_verdict_between_the_decided_ones_and_not_reproducible():
    assert VERDICTS == ("reproduced", "not_reproduced", NOT_TESTABLE, "not_reproducible")


def test_exact_bounds_at_the_extreme_counts_are_clopper_pearsons():
    n = np.array([1, 2, 3, 6, 35, 36, 200, 20.5])
    assert upper_end_with_no_success(n) == pytest.approx(clopper_pearson(np.zeros_like(n), n)[1], rel=1e-9)
    assert lower_end_with_all_successes(n) == pytest.approx(clopper_pearson(n, n)[0], rel=1e-9)


def _first(ok):
    return int(np.flatnonzero(ok)[0]) + 1


@pytest.mark.parametrize("power", [0.5, 0.8, 0.9, 0.95, 0.975])
def test_power_rule_minimum_is_the_first_n_at_which_no_success_fails(power):
    n = np.arange(1, 400)
    m = power_rule_minimum(power, "recordings").needed
    assert m == _first(clopper_pearson(0 * n, n)[1] < power)
    if power == 0.8:
        assert m == 3


@pytest.mark.parametrize("alpha", [0.01, 0.05, 0.1])
def test_rate_rule_minima_are_the_first_n_at_which_the_rule_can_pass(alpha):
    n = np.arange(1, 2000)
    assert rate_upper_rule_minimum(2 * alpha, "r").needed == _first(clopper_pearson(0 * n, n)[1] <= 2 * alpha)
    assert rate_lower_rule_minimum(alpha, "r").needed == _first(clopper_pearson(n, n)[0] > alpha)
    if alpha == 0.05:
        assert (rate_upper_rule_minimum(0.1, "r").needed, rate_lower_rule_minimum(0.05, "r").needed) == (36, 2)


def test_rank_and_bootstrap_minima():
    r = np.arange(1, 200)
    assert rank_rule_minimum("re-simulations").needed == _first(2 / (r + 1) <= 0.05) == 39
    assert rank_rule_minimum("re-simulations", level=0.9).needed == 19
    b = np.arange(1, 200)
    assert bootstrap_rule_minimum(0.05, "sets").needed == _first(1 / (b + 1) < 0.05) == 20   # 19 sets: p >= 0.05
    assert bootstrap_rule_minimum(0.01, "sets").needed == 100


def test_resolution_minimum_fits_z_standard_errors_below_the_threshold():
    m = resolution_minimum(60, 2e-6, 1e-9, 4.0, "runs")
    assert m.needed == math.ceil(60 * (4 * 2e-6 / 1e-9) ** 2)
    se_at_needed = 2e-6 * math.sqrt(60 / m.needed)
    assert 4 * se_at_needed <= 1e-9 < 4 * 2e-6 * math.sqrt(60 / (m.needed - 1))
    assert resolution_minimum(60, 1e-12, 1e-9, 4.0, "runs").needed == 1
    assert resolution_minimum(1, float("nan"), 1e-9, 4.0, "runs").needed == 2


RULE = MinimumSample(3, "recordings per row", "with fewer the rule cannot fail")


def test_judge_below_the_minimum_is_not_testable_whatever_the_rule_says():
    for passed in (True, False):
        row = CLAIM.judge(0.5, passed, "t.csv: 1 of 2 named", fmt="{:.2f}", scale=RULE.at(2))
        assert row["verdict"] == NOT_TESTABLE and row["reproduced_value"] == "0.50"
        assert row["evidence"] == ("t.csv: not testable at this scale: n 2 (recordings per row), needs n >= 3: with "
                                   "fewer the rule cannot fail; measured: 1 of 2 named")
    # at the minimum the rule decides, and it can fail
    assert CLAIM.judge(0.5, False, "t.csv: x", scale=RULE.at(3))["verdict"] == "not_reproduced"
    assert CLAIM.judge(0.5, True, "t.csv: x", scale=RULE.at(3))["verdict"] == "reproduced"
    # an exact criterion (fractional effective sizes) overrides n >= needed; an uncounted n is testable
    assert CLAIM.judge(0.5, True, "t.csv: x", scale=RULE.at(2.5, testable=True))["verdict"] == "reproduced"
    assert CLAIM.judge(0.5, False, "t.csv: x", scale=RULE.at(float("nan")))["verdict"] == "not_reproduced"


def test_not_testable_rows_must_give_the_n_they_have_and_need(tmp_path):
    row = CLAIM.judge(0.5, True, "t.csv: x", scale=RULE.at(1))
    path = write(tmp_path, "ok.csv", good_rows() + [dict(row, claim_id="scale")])
    assert assemble_ledger([path])["verdict"].tolist()[-1] == NOT_TESTABLE
    for evidence in ("t.csv: too few", "t.csv: n 1 per row", ""):
        with pytest.raises(LedgerError, match="the n it has and the n it needs"):
            validate_rows([dict(row, evidence=evidence)])
    assert validate_rows([dict(row, reproduced_value="")]).loc[0, "verdict"] == NOT_TESTABLE
