"""Ledger rows of the measured stage: valid, not reproducible, with reasons and computed analogues."""

from __future__ import annotations

import pandas as pd

from accelcal_repro.claims import COLUMNS, validate_rows
from accelcal_repro.measured.claims import measured_claims


def tables():
    summary = pd.DataFrame([
        {"recording": "xsens_mti", "estimator": "full_lls", "n_poses": 38, "residual_rms": 0.00099, "excess": 2.97,
         "reduced_chi2": 8.8, "dof": 29, "lopo_rms": 0.00142},
        {"recording": "imucal_ferraris", "estimator": "bias_lls", "n_poses": 6, "residual_rms": 0.134,
         "excess": 248.0, "reduced_chi2": 61000.0, "dof": 3, "lopo_rms": 0.29}])
    nominal = pd.DataFrame({"recording": "xsens_mti", "estimator": "full_lls", "axis": list("xyz"),
                            "rel_diff_pct": [-0.134, -0.212, -0.092]})
    params = pd.DataFrame({"recording": "xsens_mti", "estimator": ["full_lls", "full_nlls"],
                           "parameter": "bias_x", "value": [1.0, 1.001], "boot_se": [0.5, 0.5]})
    peer = pd.DataFrame({"poses": "section_list", "parameter": ["bias"] * 3 + ["scale_factor"] * 3,
                         "method": ["bias_lls"] * 3 + ["ferraris"] * 3,
                         "tool": ["accelcal"] * 3 + ["imucal"] * 3,
                         "value": [0.5, -0.6, 0.4, -0.0033, 0.0024, 0.0234],
                         "diff_to_imucal": [1.7e-4, 1.6e-4, 3.8e-5, 0, 0, 0]})
    return summary, params, nominal, peer


def test_rows_are_valid_and_not_reproducible():
    rows = measured_claims(*tables())
    assert list(rows.columns) == list(COLUMNS)
    validate_rows(rows)
    assert (rows.verdict == "not_reproducible").all()
    assert set(rows.paper) == {"burkhard2024", "batista2011"} and len(rows) == 5
    # the foundation stage has a general 'table1_field_tests' row: no clash in the ledger
    assert "table1_field_tests" not in set(rows.claim_id)
    assert rows.evidence.str.startswith("not reproducible: the paper's recordings are not public").all()


def test_evidence_carries_the_computed_analogue():
    rows = measured_claims(*tables()).set_index("claim_id")
    lab = rows.loc["table1_lab_full_lls", "evidence"]
    assert "-0.13%" in lab and "38 hand-placed poses" in lab and "2.97" not in lab and "3.0x" in lab
    field = rows.loc["table1_field_bias_lls", "evidence"]
    assert "0.17 mm/s^2" in field and "+2.34%" in field and "134 mm/s^2" in field
    assert "0.9946" in rows.loc["sec6b_calibration_parameters", "paper_value"]


def test_missing_tables_give_a_clear_placeholder():
    s, p, n, _ = tables()
    rows = measured_claims(s[s.recording == "xsens_mti"], p, n, None).set_index("claim_id")
    assert "no imucal bias-only result" in rows.loc["table1_field_bias_lls", "evidence"]
