"""The discrepancy loop runs with one BLAS thread whatever the caller's setting (accelcal.threads)."""

from __future__ import annotations

from threadpoolctl import threadpool_info, threadpool_limits

from accelcal.discrepancy import detect
from accelcal.discrepancy.rules import Rules


def _blas_threads() -> set[int]:
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


def test_the_loop_runs_on_one_blas_thread_and_the_callers_setting_returns(monkeypatch):
    seen = []
    monkeypatch.setattr(detect, "discrepancy_wander", lambda data, rules, report: seen.append(_blas_threads()))
    with threadpool_limits(limits=2, user_api="blas"):
        assert _blas_threads() == {2}
        detect.discrepancy(None, Rules())
        assert _blas_threads() == {2}
    assert seen == [{1}]
