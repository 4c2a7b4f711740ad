"""The discrepancy stage's rules: its outputs in the CI run (a broken discrepancy config fails
in one line with the other stages' configs: tests/test_config_schemas.py).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from tests.configs import ci_config

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")


TABLES = ["results/discrepancy/benchmark/scores.csv.gz", "results/discrepancy/benchmark/rates.csv",
          "results/discrepancy/benchmark/summary.csv", "results/discrepancy/benchmark/headline.csv",
          "results/discrepancy/benchmark/profiles.json", "results/discrepancy/summary.csv",
          "results/discrepancy/measured.csv", "results/discrepancy/measured/mpu6050.json",
          "results/discrepancy/adis/models.csv", "results/discrepancy/adis/session_check.csv",
          "results/claims/discrepancy.csv"]
FIGURES = ["discrepancy_fpr", "discrepancy_confusion", "discrepancy_power", "discrepancy_rows", "discrepancy_adis_allan",
           "discrepancy_measured_before_after", "discrepancy_allan"]


def test_stage_outputs_of_the_ci_run(ci_workflow):
    """The stage end to end, in the session's CI run (tests/conftest.py): every table and
    figure, one benchmark row per recording and null, the MPU-6050 (10 poses) not
    identifiable.  Its byte-identical rerun is tests/test_workflow_reruns.py's
    (a chunk, the scoring, the summary, a measured report, the ADIS analysis, the claims,
    a figure)."""
    w = ci_workflow[0]
    bench = ci_config()["discrepancy"]["benchmark"]
    for t in TABLES + ["results/discrepancy/benchmark/record_screen.csv"]:
        assert (w / t).stat().st_size > 0, t
    scores = pd.read_csv(w / TABLES[0], keep_default_na=False, na_values=[""])
    # per profile: the effect-free recordings, five effects, the pair, the outlier, the
    # constant temperature (one seed, one size at CI scale); the power-curve profile adds
    # its five effects at its extra size; one row per recording and null
    n_effects = len(ci_config()["discrepancy"]["rules"]["candidates"])
    per_profile = n_effects + 1 + 1 + bench["seeds_constant"]
    effect_free = sum(bench["seeds_none_real"] if "real" in pr else bench["seeds_none"] for pr in bench["profiles"])
    extra = n_effects * len(bench["power_curve"]["sizes_mde"]) * len(bench["power_curve"]["profiles"])
    assert (bench["seeds"], len(bench["sizes_mde"])) == (1, 1)  # the count above assumes them
    assert scores.recording.nunique() == len(bench["profiles"]) * per_profile + effect_free + extra
    # one row per recording and null, and the oracle's beside the loop's: the nulls marked
    # effect_free on the effect-free recordings only (the false-positive control)
    nulls = {r: set(g) for r, g in scores.groupby("recording").null}
    free = set(scores[scores.truth == "none"].recording)
    every = {n for n, where in bench["nulls"].items() if where == "all"} | {"oracle"}
    assert all(nulls[r] == every | (set(bench["nulls"]) if r in free else set()) for r in nulls)
    assert scores.groupby(["recording", "null"]).size().max() == 1
    for f in FIGURES:
        for ext in ("png", "pdf"):
            assert (w / "results" / "figures" / f"{f}.{ext}").stat().st_size > 0
    summ = pd.read_csv(w / "results/discrepancy/summary.csv", keep_default_na=False, na_values=[""])
    assert {"benchmark", "measured"} == set(summ.section)
    assert summ[(summ.recording == "mpu6050") & (summ.metric == "outcome")].verdict.iloc[0] == "not_identifiable"
