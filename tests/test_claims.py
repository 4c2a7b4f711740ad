"""The claims ledger: validation of rows and files, and claim checks that can fail."""

import numpy as np
import pandas as pd
import pytest

from accelcal import full_lls_batch
from accelcal.claims import (
    COLUMNS,
    Claim,
    LedgerError,
    assemble_ledger,
    at_least,
    burkhard_foundation_claims,
    validate_rows,
)
from accelcal.montecarlo import crlb_mc, summarize_crlb
from accelcal.timing import summarize_timing

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


def timing_summary(full_ratio, bias_ratio):
    """A timing summary computed (not typed) from synthetic per-problem timings."""
    rows = []
    for r in range(3):
        for p in range(5):
            rows += [("block", "full_lls", r, p, 0, 1e-4), ("block", "full_nlls", r, p, 1, full_ratio * 1e-4),
                     ("block", "bias_lls", r, p, 2, 1e-4), ("block", "bias_nlls", r, p, 3, bias_ratio * 1e-4)]
    single = pd.DataFrame(rows, columns=["interleave", "method", "repeat", "problem", "order", "seconds"])
    return summarize_timing(single)


def test_speed_claims_follow_the_measured_ratio():
    crlb = summarize_crlb(crlb_mc(1, [1e-3], 5, methods=["full_lls", "full_nlls"]))
    fast = burkhard_foundation_claims(crlb, timing_summary(40.0, 25.0)).set_index("claim_id")
    assert fast.loc["speed_full", "verdict"] == "reproduced"
    assert fast.loc["speed_full", "reproduced_value"] == "40.0×"
    assert fast.loc["speed_bias", "verdict"] == "reproduced"
    slow = burkhard_foundation_claims(crlb, timing_summary(4.0, 25.0)).set_index("claim_id")
    assert slow.loc["speed_full", "verdict"] == "not_reproduced"
    assert slow.loc["speed_bias", "verdict"] == "reproduced"
    strict = burkhard_foundation_claims(crlb, timing_summary(40.0, 25.0), speed_min_ratio=30).set_index("claim_id")
    assert strict.loc["speed_bias", "verdict"] == "not_reproduced"
    assert ">= 30x" in strict.loc["speed_bias", "claim"]
    assert fast.loc["table1_field_tests", "verdict"] == "not_reproducible"
    validate_rows(fast.reset_index())


def test_fig1a_claim_fails_for_a_wrong_full_lls():
    """A 'full LLS' whose bias is off by two noise std along x must not reproduce Fig. 1(a)."""

    def wrong_full_lls(z, g, noise_std):
        r = full_lls_batch(z, g)
        return {"bias": r.bias + [2 * noise_std, 0, 0], "M": r.M, "valid": r.valid,
                "status": np.where(r.valid, "ok", "invalid")}

    timing = timing_summary(40.0, 25.0)
    kw = dict(methods=["full_lls", "full_nlls"])
    right = summarize_crlb(crlb_mc(4, [1e-5, 1e-3], 60, **kw))
    wrong = summarize_crlb(crlb_mc(4, [1e-5, 1e-3], 60, estimators={"full_lls": wrong_full_lls}, **kw))
    ok = burkhard_foundation_claims(right, timing).set_index("claim_id").loc["fig1a_full_lls_equals_nlls"]
    bad = burkhard_foundation_claims(wrong, timing).set_index("claim_id").loc["fig1a_full_lls_equals_nlls"]
    assert ok["verdict"] == "reproduced"
    assert bad["verdict"] == "not_reproduced"
    assert float(bad["reproduced_value"].split("%")[0]) > 50
    assert "1e-05" in bad["evidence"] and "0.001" in bad["evidence"]


def test_fig1a_claim_fails_when_a_noise_level_has_no_valid_trial():
    s = summarize_crlb(crlb_mc(4, [1e-5, 1e-3], 10, methods=["full_lls", "full_nlls"]))
    s.loc[(s.noise_std == 1e-3) & (s.method == "full_lls"), "bias_rms"] = np.nan
    row = burkhard_foundation_claims(s, timing_summary(40, 25)).set_index("claim_id").loc["fig1a_full_lls_equals_nlls"]
    assert row["verdict"] == "not_reproduced"
