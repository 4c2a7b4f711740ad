"""Stage 'foundation' (Burkhard et al. 2024): Monte Carlo errors of every estimator
against the Cramér–Rao bound, LLS vs NLLS compute time, and the stage's claims."""

FIGURES.extend(["foundation_crlb", "foundation_timing"])
CLAIM_STAGES.append("foundation")

CRLB = config["foundation"]["crlb"]
TIMING = config["foundation"]["timing"]
#: noise level by its file-name key (one Monte Carlo job per noise level)
NOISE = {noise_key(x): float(x) for x in CRLB["noise_std"]}


wildcard_constraints:
    noise="|".join(re.escape(k) for k in NOISE),


rule foundation_crlb_mc:
    """Monte Carlo of the Burkhard setting at one noise level (its own random stream)."""
    output:
        "results/foundation/crlb_mc/noise_{noise}.csv",
    params:
        seed=config["seed"],
        noise_std=lambda w: NOISE[w.noise],
        trials=CRLB["trials"],
        methods=CRLB["methods"],
        als_known_noise=CRLB["als_known_noise"],
        burkhard=config["burkhard"],
    log:
        log_path("foundation/crlb_mc_noise_{noise}"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,  # about 15 ms per trial with NLLS, ALS and two CRLBs
    script:
        "../scripts/foundation_crlb_mc.py"


rule foundation_crlb_summary:
    """Gather the noise levels into one tidy table and summarise per noise × method."""
    input:
        expand("results/foundation/crlb_mc/noise_{noise}.csv", noise=NOISE),
    output:
        table="results/foundation/crlb_mc.csv",
        summary="results/foundation/crlb_summary.csv",
    log:
        log_path("foundation/crlb_summary"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/foundation_crlb_summary.py"


rule foundation_crlb_figure:
    input:
        summary="results/foundation/crlb_summary.csv",
    output:
        **figure_outputs("foundation_crlb", "../report/foundation_crlb.rst", "Foundation"),
    params:
        methods=CRLB["methods"],
    log:
        log_path("foundation/crlb_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/plot_foundation_crlb.py"


rule foundation_timing_run:
    """Benchmark: per-problem time of LLS vs NLLS side by side, and batched LLS throughput.

    threads = all cores: Snakemake then runs it alone, so no other job perturbs the clock.
    """
    output:
        single="results/foundation/timing.csv",
        batch="results/foundation/timing_batch.csv",
        summary="results/foundation/timing_summary.csv",
    params:
        seed=config["seed"],
        timing=TIMING,
        g=config["burkhard"]["g"],
        n_poses=config["burkhard"]["n_poses"],
    log:
        log_path("foundation/timing_run"),
    threads: workflow.cores
    resources:
        mem_mb=2000,
        runtime=30,
    script:
        "../scripts/foundation_timing.py"


rule foundation_timing_figure:
    input:
        single="results/foundation/timing.csv",
        summary="results/foundation/timing_summary.csv",
    output:
        **figure_outputs("foundation_timing", "../report/foundation_timing.rst", "Foundation"),
    params:
        interleave=TIMING["headline_interleave"],
    log:
        log_path("foundation/timing_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/plot_foundation_timing.py"


rule foundation_claims:
    """Burkhard (2024) claims computed from the foundation tables."""
    input:
        crlb_summary="results/foundation/crlb_summary.csv",
        timing_summary="results/foundation/timing_summary.csv",
    output:
        "results/claims/foundation.csv",
    params:
        claims=config["claims"],
        interleave=TIMING["headline_interleave"],
    log:
        log_path("foundation/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/foundation_claims.py"


# Figure ids as targets: `snakemake foundation_crlb` (target only: no job, no log).
rule foundation_crlb:
    localrule: True
    input:
        "results/figures/foundation_crlb.png",
        "results/figures/foundation_crlb.pdf",


rule foundation_timing:
    localrule: True
    input:
        "results/figures/foundation_timing.png",
        "results/figures/foundation_timing.pdf",
