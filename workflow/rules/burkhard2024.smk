"""Stage 'burkhard2024': Burkhard, Sharma, Skaloud (2024), every panel of Fig. 1, the
compute-time claim, and where the closed form stops being enough.  Config: the
`burkhard2024` mapping (workflow/schemas/burkhard2024.schema.yaml).

The experiments of the config (one per panel) are merged into one Monte Carlo job per grid
point (pose count, noise std, g error; workflow/scripts/_burkhard2024_points.py); the data
come from the random stream of (pose count, noise std), so the g errors of a point share
their trials.  A gather job writes the tidy table and its summaries, from which the
figures and the claims are computed.

Needs from common.smk: declare_stage, results, log_path, bench_path, figure_files, figure_outputs,
SMALL.
"""

import re

# The grid split into jobs reads the registry's table as JSON (standard library only), so
# that parsing imports no accelcal module (tests/test_workflow_parse.py).
from _burkhard2024_points import grid_points, unusable_methods

BURKHARD = config["burkhard2024"]


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_burkhard2024(b, cfg):
    for name, exp in b["experiments"].items():
        _check_estimators(exp["methods"], f"burkhard2024.experiments.{name}.methods")
        if unusable_methods(exp):
            raise _config_error(f"burkhard2024.experiments.{name}.methods",
                                f"{', '.join(unusable_methods(exp))} need more poses than any of n_poses "
                                f"{exp['n_poses']}")
    timing = b["timing"]
    for key, among in (("headline_interleave", "interleavings"), ("headline_n_poses", "n_poses")):
        if timing[key] not in timing[among]:
            raise _config_error(f"burkhard2024.timing.{key}", f"{timing[key]!r} is not in {among} {timing[among]}")
    # the Fig. 1(a) claims are judged over the paper's noise range: it must hold a grid level
    lo, hi = b["claims"]["paper_noise_range"]
    if not any(lo <= s <= hi for s in b["experiments"]["fig1a"]["noise_std"]):
        raise _config_error("burkhard2024.experiments.fig1a.noise_std",
                            f"no noise level in claims.paper_noise_range [{lo}, {hi}]")


check_section("burkhard2024", _check_burkhard2024)
#: Monte Carlo jobs: point key (e.g. n24_s0.0001) -> {n_poses, noise_std, cases}
BURKHARD_POINTS = grid_points(BURKHARD["experiments"])
BURKHARD_DIR = results("burkhard2024")
#: Figures by job: one job draws the panels of Fig. 1 and the limit from the gathered tables
#: and the timing figure from the benchmark (a plotting job costs more to start than to draw).
BURKHARD_FIGURE_JOBS = {
    "figures": {
        "figures": ["fig1a", "fig1b", "fig1c", "fig1d", "fig1e", "lls_limit", "timing"],
        "input": {"summary": f"{BURKHARD_DIR}/summary.csv", "limit": f"{BURKHARD_DIR}/lls_limit.csv",
                  "onsets": f"{BURKHARD_DIR}/lls_limit_onsets.csv",
                  "timing_summary": f"{BURKHARD_DIR}/timing_summary.csv",
                  "mc_timing": f"{BURKHARD_DIR}/mc_timing_summary.csv"},
    },
}
BURKHARD_FIGURES = [f for job in BURKHARD_FIGURE_JOBS.values() for f in job["figures"]]

BURKHARD_STAGE = declare_stage(
    name="burkhard2024",
    figures=[f"burkhard2024_{f}" for f in BURKHARD_FIGURES],
    tables=(
        ("Scale-factor and non-orthogonality errors across the noise range (24 poses)",
         f"{BURKHARD_DIR}/relative_errors.csv"),
        ("Where full LLS becomes measurably worse than NLLS and the CRLB", f"{BURKHARD_DIR}/lls_limit_onsets.csv"),
        ("Monte Carlo RMS error / Cramér–Rao bound per noise level (24 poses), NLLS iterations and "
         "IPOPT tolerance: the NLLS baseline stops at the accuracy the problem needs",
         f"{BURKHARD_DIR}/nlls_efficiency.csv"),
    ),
)


wildcard_constraints:
    bk_point="|".join(re.escape(k) for k in BURKHARD_POINTS),


rule burkhard2024_mc:
    """Monte Carlo of one grid point: every case (data set, g error, methods) on its data.
    With `mc_kernels: numpy` (the default) it calls no compiled kernel, so it does not wait
    for the compile job: the 30 points of the default config start at once beside it."""
    input:
        kernel_cache=[] if BURKHARD["mc_kernels"] == "numpy" else KERNEL_CACHE,
    output:
        table=f"{BURKHARD_DIR}/mc/{{bk_point}}.csv.gz",
        timing=f"{BURKHARD_DIR}/mc_timing/{{bk_point}}.csv",
    params:
        point=lambda w: BURKHARD_POINTS[w.bk_point],
        seed=BURKHARD["seed"],
        g=BURKHARD["g"],
        truth=BURKHARD["truth"],
        trials=BURKHARD["trials"],
        als_known_noise=BURKHARD["als_known_noise"],
        nlls_known_noise=BURKHARD["nlls_known_noise"],
        kernels=BURKHARD["mc_kernels"],
    log:
        log_path("burkhard2024/mc_{bk_point}"),
    benchmark:
        bench_path("burkhard2024/mc_{bk_point}"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,  # [min]; about 30 s of CPU for the largest point (24 poses, 7 methods, 1000 trials)
    script:
        "../scripts/burkhard2024_mc.py"


rule burkhard2024_summary:
    """Gather the points into the tidy table; summaries, paired comparisons, the relative
    errors across the noise range, the LLS limit and the Monte Carlo wall times."""
    input:
        tables=expand(f"{BURKHARD_DIR}/mc/{{bk_point}}.csv.gz", bk_point=BURKHARD_POINTS),
        timings=expand(f"{BURKHARD_DIR}/mc_timing/{{bk_point}}.csv", bk_point=BURKHARD_POINTS),
    output:
        table=f"{BURKHARD_DIR}/mc.csv.gz",
        summary=f"{BURKHARD_DIR}/summary.csv",
        comparisons=f"{BURKHARD_DIR}/comparisons.csv",
        relative_errors=f"{BURKHARD_DIR}/relative_errors.csv",
        limit=f"{BURKHARD_DIR}/lls_limit.csv",
        onsets=f"{BURKHARD_DIR}/lls_limit_onsets.csv",
        mc_timing=f"{BURKHARD_DIR}/mc_timing.csv",
        mc_timing_summary=f"{BURKHARD_DIR}/mc_timing_summary.csv",
        efficiency=f"{BURKHARD_DIR}/nlls_efficiency.csv",
    params:
        experiments=BURKHARD["experiments"],
        g=BURKHARD["g"],
        paper_noise_range=BURKHARD["claims"]["paper_noise_range"],
        z=BURKHARD["claims"]["z"],
        min_effect=BURKHARD["lls_limit"]["min_effect"],
    log:
        log_path("burkhard2024/summary"),
    benchmark:
        bench_path("burkhard2024/summary"),
    threads: 1
    resources:
        mem_mb=3000,
        runtime=10,
    script:
        "../scripts/burkhard2024_summary.py"


rule burkhard2024_timing_run:
    """Benchmark: per-problem time of every method side by side, per pose count (the
    closed forms with the compiled kernels and with the numpy reference implementations),
    and the batched closed forms' throughput.  The estimator part of the `benchmark`
    target (workflow/rules/benchmark.smk) and the source of the speed claims.

    threads = all cores: Snakemake then runs it alone, so no other job perturbs the clock.
    """
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        single=f"{BURKHARD_DIR}/timing.csv",
        batch=f"{BURKHARD_DIR}/timing_batch.csv",
        summary=f"{BURKHARD_DIR}/timing_summary.csv",
    params:
        seed=BURKHARD["seed"],
        g=BURKHARD["g"],
        timing=BURKHARD["timing"],
        als_known_noise=BURKHARD["als_known_noise"],
        nlls_known_noise=BURKHARD["nlls_known_noise"],
    log:
        log_path("burkhard2024/timing_run"),
    benchmark:
        bench_path("burkhard2024/timing_run"),
    threads: workflow.cores
    resources:
        mem_mb=2000,
        runtime=30,
    script:
        "../scripts/burkhard2024_timing.py"


for _job, _spec in BURKHARD_FIGURE_JOBS.items():

    rule:
        name:
            f"burkhard2024_{_job}"
        input:
            **_spec["input"],
        output:
            **{f"{fig}_{ext}": path for fig in _spec["figures"]
               for ext, path in figure_outputs(f"burkhard2024_{fig}", f"../report/burkhard2024_{fig}.rst",
                                               "Burkhard 2024").items()},
        params:
            figures=_spec["figures"],
            cfg=config_keys(BURKHARD, "experiments", "g", "timing"),  # what the figures read
        log:
            log_path(f"burkhard2024/{_job}"),
        benchmark:
            bench_path(f"burkhard2024/{_job}"),
        threads: 1
        resources:
            **SMALL,
        script:
            "../scripts/burkhard2024_figure.py"


rule burkhard2024_claims:
    """Burkhard (2024) claims computed from the summaries."""
    input:
        summary=f"{BURKHARD_DIR}/summary.csv",
        comparisons=f"{BURKHARD_DIR}/comparisons.csv",
        timing_summary=f"{BURKHARD_DIR}/timing_summary.csv",
        mc_timing_summary=f"{BURKHARD_DIR}/mc_timing_summary.csv",
    output:
        results("claims/burkhard2024.csv"),
    params:
        cfg=config_keys(BURKHARD, "experiments", "claims", "timing.headline_interleave",
                        "timing.headline_n_poses"),
    log:
        log_path("burkhard2024/claims"),
    benchmark:
        bench_path("burkhard2024/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/burkhard2024_claims.py"


rule burkhard2024:
    """Every output of the stage (target only)."""
    localrule: True
    input:
        figure_files(*BURKHARD_STAGE.figures),
        results("claims/burkhard2024.csv"),
