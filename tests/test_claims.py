"""The claims ledger: validation of rows and files, and claim checks that can fail.

The Burkhard (2024) claims are tested in tests/test_burkhard2024_checks.py."""

import pandas as pd
import pytest

from accelcal_repro.claims import COLUMNS, Claim, LedgerError, assemble_ledger, at_least, validate_rows

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
