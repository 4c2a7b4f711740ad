"""The report's summary tables stay readable: key columns, groups, folded rows (accelcal_repro.report.view_table)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal_repro.report import TABLE_VIEWS, view_table


def _summary(n_rec=8, n_est=5, extra=15):
    rows = []
    for r in range(n_rec):
        for e in range(n_est):
            row = {"recording": f"rec{r}", "estimator": f"est{e}", "n_poses": 30, "dof": 21, "residual_rms": 1e-3,
                   "predicted_rms": 8e-4, "excess": 1.2, "p_value": 0.1, "lopo_rms": 1.3e-3, "ci_method": "b",
                   "distinct_orientations": 25, "coverage": 0.8, "warnings": ""}
            row.update({f"extra_{k}": float(k) for k in range(extra)})
            rows.append(row)
    return pd.DataFrame(rows)


def test_wide_table_shows_key_columns_per_group_and_the_rest_on_demand():
    df = _summary()
    html = view_table(df, TABLE_VIEWS["results/measured/summary.csv"])
    assert html.count("<h4>recording: ") == 8
    first = html.split("<details>")[0]
    assert "extra_3" not in first and "excess" in first  # extra columns only in the folded full table
    assert "all 28 columns" in html and "extra_3" in html


def test_long_table_is_folded_after_25_rows_and_missing_columns_are_skipped():
    df = pd.DataFrame({"section": ["benchmark"] * 40 + ["measured"] * 30, "metric": [f"m{k}" for k in range(70)],
                       "value": np.arange(70.0)})
    html = view_table(df, TABLE_VIEWS["results/discrepancy/summary.csv"])
    assert html.count("<h4>section: ") == 2
    assert "15 more rows" in html and "5 more rows" in html
    assert "verdict" not in html  # the view's column the file lacks is skipped


def test_default_view_limits_columns_without_a_view():
    df = pd.DataFrame({f"c{k}": [1.0] for k in range(20)})
    html = view_table(df)
    assert "all 20 columns" in html and "c15" in html.split("<details>")[1]
