"""Stage 'tereshkov': Tereshkov's virtual-platform AHRS and closed-form bias
estimator on simulated tractor runs — Monte Carlo convergence and accuracy, straight vs
turning observability, the artificial-bias test, an installation-angle sweep, the
stage's claims and figures.  Config: the `tereshkov` mapping (section `tereshkov` of config/config.yaml).

Needs from common.smk: declare_stage, stage_figures, results, log_path, bench_path, figure_files, figure_outputs,
SMALL.
"""

TERESHKOV = config["tereshkov"]


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_tereshkov(t, cfg):
    for part in ("monte_carlo", "sweep", "comparison"):
        start, duration = t[part]["steady_state_from_s"], t[part]["duration_s"]
        if start >= duration:
            raise _config_error(f"tereshkov.{part}.steady_state_from_s",
                                f"{start} s leaves no steady state in a run of {part}.duration_s = {duration} s")
    # a job holds the runs r with r % jobs == job of every scenario it simulates
    for part, scenarios in (("monte_carlo", ("field", "straight", "artificial")), ("sweep", None)):
        runs = {sc: t["scenarios"][sc]["runs"] for sc in scenarios} if scenarios else {"sweep": t["sweep"]["runs"]}
        fewest = min(runs, key=runs.get)
        if t[part]["jobs"] > runs[fewest]:
            raise _config_error(f"tereshkov.{part}.jobs",
                                f"{t[part]['jobs']} jobs for the {runs[fewest]} runs of {fewest} would leave a job "
                                "without runs")
    e = t["estimator"]
    if e["turn_rate_dps"] <= e["straight_rate_dps"]:
        raise _config_error("tereshkov.estimator.turn_rate_dps",
                            f"{e['turn_rate_dps']} must exceed straight_rate_dps = {e['straight_rate_dps']}")
    # the external specific force is differenced GNSS velocity interpolated to the IMU samples
    for where in ("imu.rate_hz", "comparison.imu_rate_hz"):
        part, key = where.split(".")
        rate = t[part][key]
        if t["gnss"]["rate_hz"] > rate:
            raise _config_error("tereshkov.gnss.rate_hz",
                                f"{t['gnss']['rate_hz']} Hz exceeds the IMU rate {where} = {rate} Hz")


check_section("tereshkov", _check_tereshkov)
TERESHKOV_DIR = results("tereshkov")
TERESHKOV_STAGE = declare_stage(
    name="tereshkov",
    # the last: Tereshkov against the Batista et al. (2011) filter on the same runs
    figures=("tereshkov_fig2", "tereshkov_fig3", "tereshkov_fig4", "tereshkov_installation",
             "bias_convergence_comparison"),
)
#: What the simulations read (accelcal_repro.tereshkov.montecarlo): not the claims, figures or comparison.
TERESHKOV_RUNS = ("seed", "g", "imu", "gnss", "vehicle", "estimator", "monte_carlo", "scenarios", "sweep")
#: What the figures read: the estimator's settings and the paper's numbers they draw.
TERESHKOV_FIGURE_KEYS = ("estimator", "figures", "claims.gyro_convergence_s", "claims.accel_convergence_s",
                         "claims.gyro_ss_rms_dps", "claims.accel_ss_rms_mps2", "claims.installation_max_deg")
#: Scenarios of equal duration share one estimator loop (its cost is per step, not per run).
TERESHKOV_MAIN = ("field", "straight", "artificial")


rule tereshkov_simulate:
    """One job's share of the field, straight-only and artificial-bias Monte Carlo runs
    (run r in job r mod monte_carlo.jobs) through one estimator loop: tidy tables
    (run × time × sensor × axis) and the wall times."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        **{sc: f"{TERESHKOV_DIR}/chunks/{sc}_{{job}}.csv.gz" for sc in TERESHKOV_MAIN},
        timing=f"{TERESHKOV_DIR}/chunks/timing_main_{{job}}.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS),
        scenarios=list(TERESHKOV_MAIN),
        job=lambda w: int(w.job),
        jobs=TERESHKOV["monte_carlo"]["jobs"],
    wildcard_constraints:
        job=r"\d+",
    log:
        log_path("tereshkov/simulate_{job}"),
    benchmark:
        bench_path("tereshkov/simulate_{job}"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,  # about a minute for 16 runs x 1800 s at 50 Hz
    script:
        "../scripts/tereshkov_simulate.py"


rule tereshkov_sweep:
    """One job's share of the installation-angle sweep (same paths, biases and noise at
    every angle)."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        sweep=f"{TERESHKOV_DIR}/chunks/sweep_{{job}}.csv.gz",
        timing=f"{TERESHKOV_DIR}/chunks/timing_sweep_{{job}}.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS),
        scenarios=["sweep"],
        job=lambda w: int(w.job),
        jobs=TERESHKOV["sweep"]["jobs"],
    wildcard_constraints:
        job=r"\d+",
    log:
        log_path("tereshkov/sweep_{job}"),
    benchmark:
        bench_path("tereshkov/sweep_{job}"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,
    script:
        "../scripts/tereshkov_simulate.py"


def tereshkov_jobs(part, pattern, **wildcards):
    return expand(pattern, job=range(TERESHKOV[part]["jobs"]), **wildcards)


rule tereshkov_merge:
    """The jobs' tables of each scenario merged in the order of one job, and their wall times."""
    input:
        **{sc: tereshkov_jobs("monte_carlo", f"{TERESHKOV_DIR}/chunks/{sc}_{{job}}.csv.gz")
           for sc in TERESHKOV_MAIN},
        main_timing=tereshkov_jobs("monte_carlo", f"{TERESHKOV_DIR}/chunks/timing_main_{{job}}.csv"),
        sweep=tereshkov_jobs("sweep", f"{TERESHKOV_DIR}/chunks/sweep_{{job}}.csv.gz"),
        sweep_timing=tereshkov_jobs("sweep", f"{TERESHKOV_DIR}/chunks/timing_sweep_{{job}}.csv"),
    output:
        **{sc: f"{TERESHKOV_DIR}/{sc}.csv.gz" for sc in TERESHKOV_MAIN + ("sweep",)},
        timing_main=f"{TERESHKOV_DIR}/timing_main.csv",
        timing_sweep=f"{TERESHKOV_DIR}/timing_sweep.csv",
    params:
        scenarios=list(TERESHKOV_MAIN) + ["sweep"],
    log:
        log_path("tereshkov/merge"),
    benchmark:
        bench_path("tereshkov/merge"),
    threads: 1
    resources:
        mem_mb=3000,
        runtime=10,
    script:
        "../scripts/tereshkov_merge.py"


rule tereshkov_observability:
    """Pairs of runs differing by a known accelerometer-bias shift: torque change in
    straight motion vs turns (eqs. 12, 13)."""
    output:
        table=f"{TERESHKOV_DIR}/observability.csv",
        timing=f"{TERESHKOV_DIR}/timing_observability.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS),
    log:
        log_path("tereshkov/observability"),
    benchmark:
        bench_path("tereshkov/observability"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=20,
    script:
        "../scripts/tereshkov_observability.py"


rule tereshkov_headings:
    """True heading, yaw rate and speed of the example field runs (Fig. 2)."""
    output:
        f"{TERESHKOV_DIR}/headings.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS, "figures"),
    log:
        log_path("tereshkov/headings"),
    benchmark:
        bench_path("tereshkov/headings"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/tereshkov_headings.py"


rule tereshkov_summary:
    """Convergence times, steady-state errors, artificial-bias test and sweep summaries,
    and the wall times of the Monte Carlo jobs."""
    input:
        **{sc: f"{TERESHKOV_DIR}/{sc}.csv.gz" for sc in TERESHKOV_MAIN},
        sweep=f"{TERESHKOV_DIR}/sweep.csv.gz",
        timings=expand(f"{TERESHKOV_DIR}/timing_{{part}}.csv", part=("main", "sweep", "observability")),
    output:
        summary=f"{TERESHKOV_DIR}/summary.csv",
        artificial=f"{TERESHKOV_DIR}/artificial_summary.csv",
        sweep=f"{TERESHKOV_DIR}/sweep_summary.csv",
        timing=f"{TERESHKOV_DIR}/timing.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS),
    log:
        log_path("tereshkov/summary"),
    benchmark:
        bench_path("tereshkov/summary"),
    threads: 1
    resources:
        mem_mb=3000,
        runtime=10,
    script:
        "../scripts/tereshkov_summary.py"


rule tereshkov_claims:
    """Tereshkov claims computed from the summaries."""
    input:
        summary=f"{TERESHKOV_DIR}/summary.csv",
        observability=f"{TERESHKOV_DIR}/observability.csv",
        artificial=f"{TERESHKOV_DIR}/artificial_summary.csv",
        sweep=f"{TERESHKOV_DIR}/sweep_summary.csv",
    output:
        results("claims/tereshkov.csv"),
    params:
        rules=TERESHKOV["claims"],
    log:
        log_path("tereshkov/claims"),
    benchmark:
        bench_path("tereshkov/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/tereshkov_claims.py"


# ---------------------------------------------------------------------------- comparison
# Tereshkov against the Batista et al. (2011) Kalman filter on the same simulated runs.


rule tereshkov_comparison:
    """Same runs, same IMU data: Tereshkov (GNSS specific force) vs the Batista filter
    (body-frame velocity), bias errors and compute cost per step."""
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        table=f"{TERESHKOV_DIR}/comparison.csv.gz",
        summary=f"{TERESHKOV_DIR}/comparison_summary.csv",
    params:
        cfg=config_keys(TERESHKOV, *TERESHKOV_RUNS, "comparison"),
        # the Batista filter's tuning from its own stage config (paper Ξ, Θ; P0 choice)
        batista={k: v for k, v in config.get("batista2011", {}).get("filter", {}).items()
                 if k in ("xi", "theta", "P0_std")},
    log:
        log_path("tereshkov/comparison"),
    benchmark:
        bench_path("tereshkov/comparison"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,  # one 9-state Kalman filter per run, a few hundred µs per step
    script:
        "../scripts/tereshkov_comparison.py"


# One job draws every figure (rule tereshkov_figures, common.smk's stage_figures).
stage_figures(
    TERESHKOV_STAGE,
    {
        "tereshkov_fig2": {"headings": f"{TERESHKOV_DIR}/headings.csv"},
        "tereshkov_fig3": {"field": f"{TERESHKOV_DIR}/field.csv.gz", "straight": f"{TERESHKOV_DIR}/straight.csv.gz",
                           "summary": f"{TERESHKOV_DIR}/summary.csv"},
        "tereshkov_fig4": {"field": f"{TERESHKOV_DIR}/field.csv.gz", "straight": f"{TERESHKOV_DIR}/straight.csv.gz",
                           "artificial": f"{TERESHKOV_DIR}/artificial.csv.gz",
                           "summary": f"{TERESHKOV_DIR}/summary.csv"},
        "tereshkov_installation": {"sweep": f"{TERESHKOV_DIR}/sweep_summary.csv"},
        "bias_convergence_comparison": {"table": f"{TERESHKOV_DIR}/comparison.csv.gz",
                                        "summary": f"{TERESHKOV_DIR}/comparison_summary.csv"},
    },
    "Tereshkov",
    "../scripts/tereshkov_figure.py",
    params=dict(cfg=config_keys(TERESHKOV, *TERESHKOV_FIGURE_KEYS)),
    captions={"bias_convergence_comparison": "../report/tereshkov_comparison.rst"},
    resources={"mem_mb": 2000, "runtime": 10},
)


rule tereshkov:
    """The whole stage: every figure and the claims."""
    input:
        figure_files(*TERESHKOV_STAGE.figures),
        results("claims/tereshkov.csv"),
