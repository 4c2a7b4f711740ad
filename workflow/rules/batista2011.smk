"""Stage 'batista2011' (Batista, Silvestre, Oliveira, Cardeira 2011): Table I calibration
against the CRLB and the full LLS, the online bias/gravity Kalman filter (Figs. 4-8), its
observability condition, its cost per step, and the paper's claims.

Needs from common.smk: declare_stage, stage_figures, results, log_path, bench_path, figure_files, figure_outputs,
SMALL; config["batista2011"] (section batista2011 of config/config.yaml)."""

BATISTA = config["batista2011"]


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_batista2011(b, cfg):
    s = b["calibration"]["schedule"]
    # accelcal_repro.batista2011.trajectory.StepSchedule: the window must miss the transition
    if not s["transition_s"] <= s["window_start_s"] <= s["step_s"] - s["window_s"]:
        raise _config_error("batista2011.calibration.schedule.window_start_s",
                            f"the data window {s['window_start_s']}-{s['window_start_s'] + s['window_s']} s "
                            f"must lie in the static part {s['transition_s']}-{s['step_s']} s of each step")
    for part in ("calibration", "filter"):
        if b[part]["jobs"] > b[part]["runs"]:
            raise _config_error(f"batista2011.{part}.jobs",
                                f"{b[part]['jobs']} jobs for {b[part]['runs']} runs would leave a job without runs")
    f = b["filter"]
    if f["steady_from_s"] >= f["duration_s"]:
        raise _config_error("batista2011.filter.steady_from_s",
                            f"{f['steady_from_s']} s leaves no steady state in a run of filter.duration_s = "
                            f"{f['duration_s']} s")
    # the observability runs use the filter's time grid; a longer window would be cut silently
    if b["observability"]["gramian_window_s"] > f["duration_s"]:
        raise _config_error("batista2011.observability.gramian_window_s",
                            f"{b['observability']['gramian_window_s']} s exceeds the run, filter.duration_s = "
                            f"{f['duration_s']} s")


check_section("batista2011", _check_batista2011)


def batista_cfg(*sections):
    """The stage config restricted to seed, g and ``sections`` (:func:`config_keys`)."""
    return config_keys(BATISTA, "seed", "g", *sections)

BATISTA_OUT = results("batista2011")
BATISTA_STAGE = declare_stage(
    name="batista2011",
    figures=("batista2011_trajectories", "batista2011_calibration", "batista2011_fig4", "batista2011_fig5",
             "batista2011_errors", "batista2011_observability"),
)

#: Tables each figure is drawn from.
BATISTA_FIGURE_INPUTS = {
    "batista2011_trajectories": {},
    "batista2011_calibration": {
        "summary": f"{BATISTA_OUT}/calibration_summary.csv",
        "comparison": f"{BATISTA_OUT}/calibration_lls_comparison.csv",
    },
    "batista2011_fig4": {"filter_example": f"{BATISTA_OUT}/filter_example.csv.gz"},
    "batista2011_fig5": {"filter_example": f"{BATISTA_OUT}/filter_example.csv.gz"},
    "batista2011_errors": {
        "filter_summary": f"{BATISTA_OUT}/filter_summary.csv.gz",
        "filter_cost": f"{BATISTA_OUT}/filter_cost.csv",
    },
    "batista2011_observability": {
        "observability": f"{BATISTA_OUT}/observability.csv",
        "gramian": f"{BATISTA_OUT}/gramian.csv",
    },
}


def batista_chunk_runs(section, chunk):
    """[first, last + 1) run numbers of job ``chunk`` of ``section`` (calibration or filter):
    ``jobs`` contiguous blocks of nearly equal size.  Each run draws from its own stream
    (accelcal_repro.batista2011.montecarlo.run_streams), so the split changes no number."""
    c = BATISTA[section]
    edges = [round(i * c["runs"] / c["jobs"]) for i in range(c["jobs"] + 1)]
    return [edges[int(chunk)], edges[int(chunk) + 1]]


def batista_chunks(section, pattern):
    return expand(pattern, chunk=range(BATISTA[section]["jobs"]))


rule batista2011_calibration_mc:
    """One chunk of the Table I Monte Carlo (and the linear-only variant and the full LLS
    on the same simulated noise): the error of every run, data set, method and parameter."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        f"{BATISTA_OUT}/chunks/calibration_errors_{{chunk}}.csv.gz",
    params:
        cfg=batista_cfg("calibration"),
        runs=lambda w: batista_chunk_runs("calibration", w.chunk),
    wildcard_constraints:
        chunk=r"\d+",
    log:
        log_path("batista2011/calibration_mc_{chunk}"),
    benchmark:
        bench_path("batista2011/calibration_mc_{chunk}"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=15,  # about 10 ms per run and data set
    script:
        "../scripts/batista2011_calibration_mc.py"


rule batista2011_calibration_merge:
    """The chunks merged into Table I's error table; its summary against the CRLB and the
    comparison with the full LLS."""
    input:
        chunks=batista_chunks("calibration", f"{BATISTA_OUT}/chunks/calibration_errors_{{chunk}}.csv.gz"),
    output:
        errors=f"{BATISTA_OUT}/calibration_errors.csv.gz",
        bounds=f"{BATISTA_OUT}/calibration_bounds.csv",
        summary=f"{BATISTA_OUT}/calibration_summary.csv",
        comparison=f"{BATISTA_OUT}/calibration_lls_comparison.csv",
    params:
        cfg=batista_cfg("calibration"),
    log:
        log_path("batista2011/calibration_merge"),
    benchmark:
        bench_path("batista2011/calibration_merge"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    script:
        "../scripts/batista2011_calibration_merge.py"


rule batista2011_filter_mc:
    """One chunk of the filter Monte Carlo (shared gain sequence, per-run gyro readings):
    per-run errors and the mergeable statistics over its runs."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        runs=f"{BATISTA_OUT}/chunks/filter_runs_{{chunk}}.csv.gz",
        moments=f"{BATISTA_OUT}/chunks/filter_moments_{{chunk}}.csv.gz",
    params:
        cfg=batista_cfg("filter"),
        runs=lambda w: batista_chunk_runs("filter", w.chunk),
    wildcard_constraints:
        chunk=r"\d+",
    log:
        log_path("batista2011/filter_mc_{chunk}"),
    benchmark:
        bench_path("batista2011/filter_mc_{chunk}"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=15,  # about 1 µs per run and step
    script:
        "../scripts/batista2011_filter_mc.py"


rule batista2011_filter_merge:
    """The filter chunks merged: per-run errors and the statistics over all runs (Figs. 6-8)."""
    input:
        runs=batista_chunks("filter", f"{BATISTA_OUT}/chunks/filter_runs_{{chunk}}.csv.gz"),
        moments=batista_chunks("filter", f"{BATISTA_OUT}/chunks/filter_moments_{{chunk}}.csv.gz"),
    output:
        runs=f"{BATISTA_OUT}/filter_runs.csv.gz",
        summary=f"{BATISTA_OUT}/filter_summary.csv.gz",
    log:
        log_path("batista2011/filter_merge"),
    benchmark:
        bench_path("batista2011/filter_merge"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    script:
        "../scripts/batista2011_filter_merge.py"


rule batista2011_filter_example:
    """One run of the exact filter (its own covariance): Figs. 4 and 5."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        f"{BATISTA_OUT}/filter_example.csv.gz",
    params:
        cfg=batista_cfg("filter"),
    log:
        log_path("batista2011/filter_example"),
    benchmark:
        bench_path("batista2011/filter_example"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    script:
        "../scripts/batista2011_filter_example.py"


rule batista2011_error_budget:
    """Steady-state filter errors with one noise source at a time."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        f"{BATISTA_OUT}/filter_error_budget.csv",
    params:
        cfg=batista_cfg("filter"),
    log:
        log_path("batista2011/error_budget"),
    benchmark:
        bench_path("batista2011/error_budget"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    script:
        "../scripts/batista2011_error_budget.py"


rule batista2011_filter_cost:
    """Wall time per filter step. threads = all cores: Snakemake runs it alone (clean clock)."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        f"{BATISTA_OUT}/filter_cost.csv",
    params:
        cfg=batista_cfg("filter"),
    log:
        log_path("batista2011/filter_cost"),
    benchmark:
        bench_path("batista2011/filter_cost"),
    threads: workflow.cores
    resources:
        mem_mb=1000,
        runtime=10,
    script:
        "../scripts/batista2011_filter_cost.py"


rule batista2011_observability_mc:
    """The filter with ω along a fixed axis and with a changing axis; observability Gramian."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        table=f"{BATISTA_OUT}/observability.csv",
        gramian=f"{BATISTA_OUT}/gramian.csv",
    params:
        cfg=batista_cfg("filter", "observability"),
    log:
        log_path("batista2011/observability_mc"),
    benchmark:
        bench_path("batista2011/observability_mc"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    script:
        "../scripts/batista2011_observability.py"


# One job draws every figure (rule batista2011_figures, common.smk's stage_figures).
stage_figures(
    BATISTA_STAGE,
    BATISTA_FIGURE_INPUTS,
    "Batista 2011",
    "../scripts/batista2011_figures.py",
    # what the figures read: the designs and filters they draw, the thresholds of the calibration figure
    params=dict(cfg=config_keys(BATISTA, "seed", "g", "calibration", "filter", "observability",
                                "claims.mean_threshold", "claims.std_threshold")),
)


rule batista2011_claims:
    """Batista (2011) claims computed from the stage's tables."""
    input:
        summary=f"{BATISTA_OUT}/calibration_summary.csv",
        filter_summary=f"{BATISTA_OUT}/filter_summary.csv.gz",
        filter_runs=f"{BATISTA_OUT}/filter_runs.csv.gz",
        observability=f"{BATISTA_OUT}/observability.csv",
        gramian=f"{BATISTA_OUT}/gramian.csv",
        error_budget=f"{BATISTA_OUT}/filter_error_budget.csv",
    output:
        results("claims/batista2011.csv"),
    params:
        cfg=config_keys(BATISTA, "claims", "filter.bias", "filter.noise.accel", "filter.steady_from_s",
                        "observability.runs"),
    log:
        log_path("batista2011/claims"),
    benchmark:
        bench_path("batista2011/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/batista2011_claims.py"


rule batista2011:
    """The whole stage: every figure and the claims."""
    input:
        figure_files(*BATISTA_STAGE.figures),
        results("claims/batista2011.csv"),
