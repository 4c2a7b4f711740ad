"""Stage 'gyro': the gyroscope calibrated from the same sessions as the accelerometer.

The integrator study (scale-factor bias vs rotation rate and sample rate), the Monte
Carlo of the one-step and the iterative estimate against the Cramér–Rao bound (and their
time per problem, apart: wall times), the Gauss-Newton fit against IPOPT on the same cost,
and every real session with gyro data calibrated as `accelcal calibrate` does, beside the
peers: IMU-TK's published .calib files of the fork sessions, imucal run as a package on its
own example session, the Xsens data-sheet values, and, when `gyro.imutk_run` names it,
IMU-TK built from source and run outside the workflow (tools/gyro_peers.py records it: no
download or build at run time).  Claims with computed verdicts (paper key `gyro`).
Config: the `gyro` mapping (workflow/schemas/gyro.schema.yaml).

The data are fetched by a job per dataset (gyro_fetch: the shared copy, else a verified
download), as the measured stage's.

Needs from common.smk: declare_stage, stage_figures, results, log_path, bench_path, figure_files,
figure_outputs, measured_data_dir, SMALL; the `measured` config's resources_dir.
"""

import os

GYRO = config["gyro"]
#: The sessions' table of accelcal_repro.gyro.sessions (its data file, read without importing it).
GYRO_TABLE = repro_table("gyro_sessions.json")


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_gyro(g, cfg):
    _check_names(g["sessions"], list(GYRO_TABLE["sessions"]), "gyro.sessions", "a gyro session")


check_section("gyro", _check_gyro)
GYRO_DIR = results("gyro")
#: {dataset: files} of the configured sessions (and the CTU rotations).
# (a session's files as accelcal_repro.gyro.sessions.SessionSpec.files orders them)
GYRO_DATASETS = dataset_files([(GYRO_TABLE["ctu"][0], GYRO_TABLE["ctu"][1:])] + [
    (s["dataset"], [s.get(k) for k in ("acc", "gyro", "intervals")] + s.get("calib", []))
    for s in map(GYRO_TABLE["sessions"].get, GYRO["sessions"])])
GYRO_MANIFEST = results("gyro/data/{dataset}.json")
GYRO_SESSION_TABLES = ("sessions", "sessions_timing", "parameters", "peer_parameters", "figure_of_merit", "stability",
                       "imucal_parameters", "imucal_figure_of_merit", "ctu_parameters")
#: IMU-TK's run from source (tools/gyro_peers.py), if the config names it (relative to the project root).
GYRO_IMUTK_RUN = ([os.path.normpath(os.path.join(workflow.basedir, GYRO["imutk_run"]))]
                  if GYRO["imutk_run"] else [])
GYRO_STAGE = declare_stage(
    name="gyro",
    figures=("gyro_integrator_bias", "gyro_crlb", "gyro_figure_of_merit"),
    tables=(("Real sessions: how the gyro fit the noise, and the refusals",
             results("gyro/sessions/sessions.csv")),
            ("Figure of merit: gravity carried from rest to rest by each calibration [deg]",
             results("gyro/sessions/figure_of_merit.csv")),
            ("Parameters against the peers, in accelcal's standard errors", results("gyro/sessions/peer_parameters.csv")),
            ("imucal's session: accelcal's Ferraris fit and imucal's", results("gyro/sessions/imucal_parameters.csv")),
            ("Session-to-session stability (IMU-TK fork data1-4, SNU good1-3)", results("gyro/sessions/stability.csv")),
            ("Monte Carlo: median RMS error / CRLB per configuration", results("gyro/montecarlo_summary.csv")),
            ("Coverage of the 95 % intervals with a wandering bias", results("gyro/coverage_summary.csv")),
            ("Monte Carlo: time per problem (wall times)", results("gyro/montecarlo_timing.csv")),
            ("The gyro loop's benchmark: false positives and power per candidate at multiples of its MDE",
             results("gyro/loop/benchmark_summary.csv")),
            ("The gyro loop on the real sessions: effects named, excess before/after", results("gyro/loop/sessions.csv")),
            ("Named gyro effects across sessions of one unit: do their estimates agree?",
             results("gyro/loop/repeats.csv"))),
    summaries=(("Real sessions: each gyroscope calibration", summaries_path("gyro_sessions")),),
)


wildcard_constraints:
    dataset="|".join(GYRO_DATASETS),


rule gyro_fetch:
    """Locate (shared copy) or download and verify (sha256) the files of one dataset the
    sessions need, as measured_fetch does; high priority: a failing download stops the run early."""
    priority: 100
    localrule: True  # on a cluster: the login node (internet access; a checksum when the data is local)
    output:
        GYRO_MANIFEST,
    params:
        files=lambda w: list(GYRO_DATASETS[w.dataset]),
        data_dir=measured_data_dir(),
        resources_dir=config["measured"]["resources_dir"],
    log:
        log_path("gyro/fetch_{dataset}"),
    benchmark:
        bench_path("gyro/fetch_{dataset}"),
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,
    script:
        "../scripts/gyro_fetch.py"


rule gyro_integrators:
    """Scale-factor bias and angle error of five integrators on simulated motions."""
    output:
        results("gyro/integrators.csv"),
    params:
        gyro=config_keys(GYRO, "seed", "integrators"),
    log:
        log_path("gyro/integrators"),
    benchmark:
        bench_path("gyro/integrators"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/gyro_integrators.py"


rule gyro_montecarlo:
    """One-step and iterative gyro estimates against the Cramér–Rao bound."""
    output:
        table=results("gyro/montecarlo.csv"),
        summary=results("gyro/montecarlo_summary.csv"),
        timing=results("gyro/montecarlo_timing.csv"),
    params:
        gyro=config_keys(GYRO, "seed", "monte_carlo"),
    log:
        log_path("gyro/montecarlo"),
    benchmark:
        bench_path("gyro/montecarlo"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=20,  # default config: about 30 s
    script:
        "../scripts/gyro_montecarlo.py"


rule gyro_coverage:
    """Coverage of the gyro's 95 % intervals in a Monte Carlo with a wandering bias.

    Priority: the longest single job outside the benchmark chunks (85 s in a fresh clone),
    with no input; started when the scheduler reached it (at 731 s of 891) it ended after
    every other job of its kind, with a core idle.  Early, it runs beside the others."""
    output:
        table=results("gyro/coverage.csv"),
        summary=results("gyro/coverage_summary.csv"),
    params:
        gyro=config_keys(GYRO, "seed", "coverage"),
    log:
        log_path("gyro/coverage"),
    benchmark:
        bench_path("gyro/coverage"),
    priority: 50
    threads: 1
    resources:
        mem_mb=1000,
        runtime=20,  # default config: about 2 min
    script:
        "../scripts/gyro_coverage.py"


rule gyro_ipopt:
    """The Gauss-Newton gyro fit against CasADi/IPOPT on the same cost."""
    output:
        table=results("gyro/ipopt_check.csv"),
        timing=results("gyro/ipopt_timing.csv"),
    params:
        gyro=config_keys(GYRO, "seed", "ipopt_check"),
    log:
        log_path("gyro/ipopt"),
    benchmark:
        bench_path("gyro/ipopt"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/gyro_ipopt.py"


rule gyro_sessions:
    """Every configured real session calibrated (accelerometer and gyro, the CLI's route),
    beside the peers; the figure of merit and the stability of the parameters."""
    input:
        manifests=expand(GYRO_MANIFEST, dataset=list(GYRO_DATASETS)),
        imutk_run=GYRO_IMUTK_RUN,
    output:
        **{t: results(f"gyro/sessions/{t}.csv") for t in GYRO_SESSION_TABLES},
        summaries=summaries_path("gyro_sessions"),
    params:
        sessions=GYRO["sessions"],
    log:
        log_path("gyro/sessions"),
    benchmark:
        bench_path("gyro/sessions"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=15,
    script:
        "../scripts/gyro_sessions.py"


rule gyro_loop_benchmark:
    """The gyro loop on simulated sessions: FPR (anything named on effect-free sessions) with its
    interval, and power per candidate at the configured multiples of its MDE."""
    output:
        cases=results("gyro/loop/benchmark_cases.csv"),
        summary=results("gyro/loop/benchmark_summary.csv"),
    params:
        gyro=config_keys(GYRO, "seed", "loop.benchmark", "loop.noise"),
    log:
        log_path("gyro/loop_benchmark"),
    benchmark:
        bench_path("gyro/loop_benchmark"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=30,  # default config: about 10 s of CPU; paper scale (300 / 20): about 20 min
    script:
        "../scripts/gyro_loop_benchmark.py"


rule gyro_loop_sessions:
    """Every configured real gyro session through the gyro loop; which named effects repeat
    across sessions of one unit (their estimates agree within their standard errors)."""
    input:
        manifests=expand(GYRO_MANIFEST, dataset=list(GYRO_DATASETS)),
    output:
        sessions=results("gyro/loop/sessions.csv"),
        repeats=results("gyro/loop/repeats.csv"),
    params:
        gyro=config_keys(GYRO, "loop.sessions", "loop.benchmark.n_boot", "loop.noise"),
    log:
        log_path("gyro/loop_sessions"),
    benchmark:
        bench_path("gyro/loop_sessions"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=15,
    script:
        "../scripts/gyro_loop_sessions.py"


rule gyro_claims:
    """Ledger rows of the gyro stage, each verdict computed from its tables."""
    input:
        integrators=results("gyro/integrators.csv"),
        montecarlo=results("gyro/montecarlo.csv"),
        ipopt=results("gyro/ipopt_check.csv"),
        figure_of_merit=results("gyro/sessions/figure_of_merit.csv"),
        peer_parameters=results("gyro/sessions/peer_parameters.csv"),
        imucal_parameters=results("gyro/sessions/imucal_parameters.csv"),
        coverage=results("gyro/coverage_summary.csv"),
        stability=results("gyro/sessions/stability.csv"),
        loop=results("gyro/loop/benchmark_summary.csv"),
    output:
        results("claims/gyro.csv"),
    log:
        log_path("gyro/claims"),
    benchmark:
        bench_path("gyro/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/gyro_claims.py"


# One job draws every figure (rule gyro_figures, common.smk's stage_figures).
stage_figures(
    GYRO_STAGE,
    {
        "gyro_integrator_bias": {"table": results("gyro/integrators.csv")},
        "gyro_crlb": {"table": results("gyro/montecarlo.csv")},
        "gyro_figure_of_merit": {"table": results("gyro/sessions/figure_of_merit.csv"),
                                 "imucal": results("gyro/sessions/imucal_figure_of_merit.csv")},
    },
    "Gyroscope",
    "../scripts/gyro_figure.py",
)


rule gyro:
    """The whole stage: tables, claims and figures."""
    input:
        expand(results("gyro/sessions/{t}.csv"), t=GYRO_SESSION_TABLES),
        results("gyro/montecarlo_summary.csv"),
        results("gyro/coverage_summary.csv"),
        results("gyro/ipopt_check.csv"),
        results("gyro/loop/benchmark_summary.csv"),
        results("gyro/loop/sessions.csv"),
        results("claims/gyro.csv"),
        figure_files(*GYRO_STAGE.figures),
