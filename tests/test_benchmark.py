"""The benchmark target: timing tables per backend, filter timing, the headline table
against the goals, job-seconds per stage, and the target's outputs in the CI run.

Wall times are never asserted on: the tables are checked for what they contain (every
method, backend and pose count; speed-ups computed from paired timings with a fake clock).
"""

import os
import subprocess
import sys
from functools import partial

import numpy as np
import pandas as pd
import pytest

from accelcal import kernels
from accelcal.registry import estimators
from accelcal.tereshkov.estimator import TereshkovParams
from accelcal_repro import first_calls, timing
from accelcal_repro.cost import headline, plot_cost

BACKENDS = timing.available_backends()


class FakeClock:
    def __init__(self):
        self.t, self.cost = 0.0, 0.0

    def __call__(self):
        self.t += self.cost
        return self.t


def test_interleaved_timing_per_backend_and_paired_speedups():
    clock = FakeClock()
    seen = []

    def method(cost_numba, cost_numpy):
        def f(z, g):
            seen.append(kernels.backend())
            clock.cost = cost_numba if kernels.backend() == "numba" else cost_numpy
        return f

    z = np.zeros((3, 24, 3))
    previous = kernels.choice()
    methods = {("full_lls", "numba"): method(5e-6, 5e-6), ("full_lls", "numpy"): method(4e-5, 4e-5),
               ("full_nlls", "casadi"): method(1e-3, 1e-3)}
    if "numba" not in BACKENDS:
        pytest.skip("numba (the optional fast extra) is not installed: only the numpy path runs")
    single = timing.time_interleaved({k: z for k in methods}, 9.8, methods, repeats=2, clock=clock)
    assert kernels.choice() == previous  # the backend is restored
    assert set(map(tuple, single[["method", "backend"]].drop_duplicates().to_numpy())) == set(methods)
    s = timing.summarize_timing(single.assign(n_poses=24)).set_index(["method", "backend"])
    assert s.loc[("full_lls", "numba"), "speedup_median"] == pytest.approx(200)
    assert s.loc[("full_lls", "numpy"), "speedup_median"] == pytest.approx(25)
    assert s.loc[("full_lls", "numba"), "baseline"] == "full_nlls"
    assert timing.preferred_backend(s.reset_index(), "full_lls") == "numba"


def test_benchmark_times_every_backend_and_the_nlls_once():
    single, batch = timing.run_benchmark(0, 9.8055, 1e-3, n_poses=[12], n_problems=2, repeats=1, batch_problems=4,
                                         batch_repeats=1, interleavings=["block"])
    pairs = set(map(tuple, single[["method", "backend"]].drop_duplicates().to_numpy()))
    assert pairs == {(m, b) for m in ("full_lls", "full_als", "bias_lls") for b in BACKENDS} | \
        {("full_nlls", "casadi"), ("bias_nlls", "casadi")}
    assert set(map(tuple, batch[["method", "backend"]].drop_duplicates().to_numpy())) == \
        {(m, b) for m in timing.BATCH_METHODS for b in BACKENDS}
    assert (single["status"] == "ok").all()


def test_batched_calls_per_backend():
    """With calls per backend, each backend's methods are timed that many times (the
    compiled batched calls are quick, and their median needs more of them)."""
    single, batch = timing.run_benchmark(0, 9.8055, 1e-3, n_poses=[12], n_problems=2, repeats=1, batch_problems=4,
                                         batch_repeats={"numpy": 1, "numba": 4}, interleavings=["block"])
    counts = batch.groupby(["method", "backend"]).size()
    assert {b: set(counts.xs(b, level="backend")) for b in BACKENDS} == \
        {b: {4 if b == "numba" else 1} for b in BACKENDS}


def _tereshkov_data(runs=2, n=300):
    f = np.zeros((runs, n, 3))
    f[..., 2] = -9.80665
    return {"gyro": np.zeros((runs, n, 3)), "accel": f.copy(), "f_ext": f, "course": np.zeros((runs, n)),
            "speed": np.full((runs, n), 5.0), "dt": 0.04, "params": TereshkovParams()}


def test_filter_timing_rows_per_backend():
    calls = []

    def batista_cost(steps):
        calls.append((kernels.backend(), steps))
        return pd.DataFrame({"implementation": ["kalman_filter (own covariance, 1 run)"], "runs": [1],
                             "steps": [100], "seconds": [1e-3]})

    t = timing.filter_timing(batista_cost, _tereshkov_data(), repeat=1)
    assert [c for c in calls] == [(b, s) for b in BACKENDS for s in (50, None)]  # warm-up, then timed
    assert set(t["backend"]) == set(BACKENDS)
    assert set(t["implementation"]) == {"kalman_filter (own covariance, 1 run)", "run_estimator (1 run)",
                                        "run_estimator (2 runs)"}
    r = t[(t["filter"] == "batista")].iloc[0]
    assert r["us_per_step"] == pytest.approx(10.0)
    batched = t[t["implementation"] == "run_estimator (2 runs)"].iloc[0]
    assert batched["us_per_run_step"] == pytest.approx(batched["us_per_step"] / 2)


def test_compile_timing_refuses_unknown_calls():
    with pytest.raises(ValueError, match="unknown first call"):
        timing.compile_timing(["full_lls", "warp_drive"])


COPY_CHECK = """
import json, os, sys
from accelcal_repro import first_calls, timing
if sys.argv[1] == "copy":
    print(timing.copy_kernel_cache(sys.argv[2]))
else:
    sys.argv[1:] = [json.dumps(["bias_lls"])]
    exec(first_calls.SCRIPT)
"""


def _cache_files(folder):
    return sorted(p.relative_to(folder) for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc"))


@pytest.mark.skipif("numba" not in BACKENDS, reason="numba not installed")
def test_a_copied_kernel_cache_loads_without_compiling(tmp_path):
    """The compile job compiles once, in an empty folder of its own, and copies that cache
    into the project's (copy_kernel_cache): the copy holds every file, no lock, and a fresh
    process with it compiles nothing (it would write new files)."""
    timed, project = tmp_path / "timed", tmp_path / "project"
    env = dict(os.environ, ACCELCAL_KERNELS="numba")

    def run(cache, *args):
        out = subprocess.run([sys.executable, "-c", COPY_CHECK, *args], env=dict(env, NUMBA_CACHE_DIR=str(cache)),
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        return out.stdout.strip().splitlines()[-1]

    run(timed, "first")  # compiles bias_lls into the empty folder
    written = _cache_files(timed)
    assert written and any(p.suffix == ".nbc" for p in written)
    assert int(run(project, "copy", str(timed))) == len(written)
    assert _cache_files(project) == written
    assert not [p for p in project.rglob("*") if p.name.endswith("compile-lock")]
    run(project, "first")  # loads: a compilation would add files
    assert _cache_files(project) == written


def test_first_call_script_names_every_call_and_calls_what_it_names():
    """The script run in fresh processes by compile_timing: its calls are FIRST_CALLS, each
    calling the estimator or filter it names (checked without running them: that compiles)."""
    script = first_calls.SCRIPT
    head = script[:script.index("wanted = ")]
    namespace = {}
    exec(compile(head.replace("import numba\n", ""), "<first calls>", "exec"), namespace)
    assert [name for name, _ in namespace["calls"]] == list(timing.FIRST_CALLS)
    for name, call in namespace["calls"]:
        assert isinstance(call, partial), name
        if hasattr(call.func, "__self__"):  # an estimator's call, from the registry
            assert call.func.__self__.name == name.split(" ")[0].removesuffix("_batch"), name
        else:  # a filter's
            assert name in first_calls.FILTER_CALLS and call.func.__name__ in name, name
    # every registered estimator with a compiled kernel has its first calls timed
    for e in estimators("accelerometer", compiled=True):
        assert e.name in timing.FIRST_CALLS and e.batch_name in timing.FIRST_CALLS, e.name


def _tables():
    est = pd.DataFrame([
        {"n_poses": 24, "mode": "single", "interleave": "block", "method": "full_lls", "backend": "numba",
         "median_s": 4e-6, "speedup_median": 300.0, "problems_per_s": 2.5e5},
        {"n_poses": 24, "mode": "single", "interleave": "block", "method": "full_lls", "backend": "numpy",
         "median_s": 4e-5, "speedup_median": 30.0, "problems_per_s": 2.5e4},
        {"n_poses": 24, "mode": "single", "interleave": "block", "method": "bias_lls", "backend": "numba",
         "median_s": 5e-6, "speedup_median": 150.0, "problems_per_s": 2e5},
        {"n_poses": 24, "mode": "single", "interleave": "block", "method": "full_nlls", "backend": "casadi",
         "median_s": 1.2e-3, "speedup_median": np.nan, "problems_per_s": 800.0},
        {"n_poses": 24, "mode": "batch", "interleave": "block", "method": "bias_lls_batch", "backend": "numba",
         "median_s": 2e-7, "speedup_median": np.nan, "problems_per_s": 3e6, "problems_per_cpu_s": 5e6},
        {"n_poses": 10, "mode": "single", "interleave": "block", "method": "full_lls", "backend": "numba",
         "median_s": 1e-4, "speedup_median": 40.0, "problems_per_s": 1e4},
    ])
    filters = pd.DataFrame([
        {"filter": "batista", "implementation": "kalman_filter (own covariance, 1 run)", "backend": "numba",
         "runs": 1, "steps": 10, "seconds": 1e-5, "us_per_step": 1.0, "us_per_run_step": 1.0},
        {"filter": "batista", "implementation": "kalman_filter (own covariance, 1 run)", "backend": "numpy",
         "runs": 1, "steps": 10, "seconds": 1e-3, "us_per_step": 100.0, "us_per_run_step": 100.0},
        {"filter": "tereshkov", "implementation": "run_estimator (1 run)", "backend": "numba",
         "runs": 1, "steps": 10, "seconds": 3e-5, "cpu_seconds": 1e-5, "us_per_step": 3.0, "us_per_run_step": 3.0},
    ])
    compile_times = pd.DataFrame({"call": ["import numba", "full_lls", "bias_lls"], "cold_s": [0.3, 5.0, 1.0],
                                  "cached_s": [0.3, 0.4, 0.01]})
    stages = pd.DataFrame({"stage": ["burkhard2024", "tereshkov"], "jobs": [3, 2], "s": [10.0, 5.0],
                           "cpu_s": [8.0, 4.5], "max_rss": [100.0, 90.0]})
    return est, filters, compile_times, stages


def test_headline_judges_the_default_implementation_against_the_goals():
    goals = {"full_lls_speedup": 200.0, "bias_lls_speedup": 200.0, "full_lls_batch_per_s": 1e6,
             "bias_lls_batch_per_s": 4e6, "batista_us_per_step": 5.0, "tereshkov_us_per_step": 2.0}
    h = headline(*_tables(), goals).set_index(["quantity", "backend"])
    assert h.loc[("speed-up full NLLS / full LLS", "numba"), "meets_goal"] == "yes"
    assert h.loc[("speed-up full NLLS / full LLS", "numpy"), "meets_goal"] == ""  # the reference is not judged
    assert h.loc[("speed-up bias-only NLLS / bias-only LLS", "numba"), "meets_goal"] == "no"
    assert h.loc[("batched bias-only LLS", "numba"), "meets_goal"] == "no"  # 3e6/s of wall time
    assert h.loc[("batched bias-only LLS (CPU time)", "numba"), "meets_goal"] == "yes"  # 5e6/s of CPU time
    assert h.loc[("Batista filter (own covariance), one run", "numba"), "meets_goal"] == "yes"
    assert h.loc[("Tereshkov estimator, one run", "numba"), "meets_goal"] == "no"  # 3 us > 2 us
    assert h.loc[("Tereshkov estimator, one run (CPU time)", "numba"), "value"] == pytest.approx(1.0)
    assert h.loc[("full LLS, one problem", "numba"), "value"] == pytest.approx(4.0)  # 24 poses, in µs
    assert h.loc[("first calls of the compiled kernels, empty cache (compilation)", "numba"), "value"] == \
        pytest.approx(6.0)  # the kernels, not the imports
    assert h.loc[("stage burkhard2024: 3 jobs, CPU seconds", ""), "value"] == pytest.approx(8.0)


def test_cost_figure_draws_with_and_without_measurements():
    import matplotlib.pyplot as plt

    est, filters, compile_times, stages = _tables()
    for fig in (plot_cost(est, filters, compile_times, stages),
                plot_cost(est, filters, compile_times.iloc[:0], stages.iloc[:0])):
        assert len(fig.axes) == 4
        plt.close(fig)


def test_stage_job_seconds_sum_wall_and_cpu(tmp_path):
    head = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    for job, s, cpu in (("burkhard2024/mc_a", 3.0, 2.5), ("burkhard2024/mc_b", 1.0, 0.75), ("claims", 0.5, 0.25)):
        f = tmp_path / f"{job}.tsv"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(head + f"{s}\t0:00:03\t100\t1\t1\t1\t0\t0\t50\t{cpu}\n")
    t = timing.stage_job_seconds(tmp_path).set_index("stage")
    assert t.loc["burkhard2024", "jobs"] == 2
    assert t.loc["burkhard2024", "s"] == pytest.approx(4.0)
    assert t.loc["burkhard2024", "cpu_s"] == pytest.approx(3.25)
    assert t.loc["claims", "cpu_s"] == pytest.approx(0.25)


def test_benchmark_outputs_of_the_ci_run(ci_workflow):
    res = ci_workflow[0] / "results"
    summary = pd.read_csv(res / "timing" / "summary.csv")
    for q in ("speed-up full NLLS / full LLS", "speed-up bias-only NLLS / bias-only LLS", "batched full LLS",
              "batched bias-only LLS", "Batista filter (own covariance), one run", "Tereshkov estimator, one run"):
        assert set(summary.loc[summary["quantity"] == q, "backend"]) == set(BACKENDS), q
    assert (summary.loc[summary["goal"].notna() & (summary["backend"] == BACKENDS[0]), "meets_goal"]
            .isin(["yes", "no"])).all()
    stages = pd.read_csv(res / "timing" / "stages.csv")
    assert {"burkhard2024", "batista2011", "tereshkov", "measured"} <= set(stages["stage"])
    compile_times = pd.read_csv(res / "timing" / "compile.csv")
    if "numba" in BACKENDS:
        assert {"import numba", "bias_lls"} <= set(compile_times["call"])
    for ext in ("png", "pdf"):
        assert (res / "figures" / f"timing_benchmark.{ext}").stat().st_size > 5000
    eff = pd.read_csv(res / "burkhard2024" / "nlls_efficiency.csv")
    nlls = eff[eff["method"].str.endswith("_nlls")]
    assert (nlls["iterations_mean"] >= 1).all() and (nlls["ipopt_tol"] <= 1e-8).all()
