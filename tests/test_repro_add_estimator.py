"""The toy estimator of docs/extending.md run through the Monte Carlo of the reproductions (accelcal_repro.montecarlo).

Moved from tests/test_add_estimator.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

from __future__ import annotations

from accelcal_repro.montecarlo import compare_methods, mc_point, summarize
from tests.test_add_estimator import toy


def test_the_toy_runs_in_the_monte_carlo(toy):
    df, timing = mc_point(7, 12, 1e-3, [("bias", 0.0, ["bias_nlls", "bias_gn"])], 4)
    assert set(df["method"]) == {"bias_nlls", "bias_gn"} and df["valid"].all()
    s = summarize(df)
    assert s.set_index("method").loc["bias_gn", "model"] == "bias"
    # Gauss-Newton and IPOPT minimise the same cost: the same estimate to the solvers' accuracy
    c = compare_methods(df, pairs=[("bias_gn", toy.baseline)])
    assert abs(c.loc[0, "bias_ratio"] - 1) < 1e-3
