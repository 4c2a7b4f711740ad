"""Target 'benchmark': where the compute time goes.  Time per problem vs pose count of every
estimator, one problem at a time and batched, compiled kernels and numpy reference (the
burkhard2024 timing job, which the speed claims also read), the cost per step of the
Batista and Tereshkov filters, the first-call (compilation) time of the kernels, and the
job-seconds of every stage of the last run; one table and one figure.  Config: the
`benchmark` mapping (workflow/schemas/benchmark.schema.yaml).

Outputs live under results/timing/ and the figure id contains "timing": wall times are
not reproducible, and the byte-identical rerun check leaves such paths out.

Needs from common.smk: declare_stage, results, figure_ids, log_path, bench_path, figure_files,
figure_outputs, SMALL.
"""

BENCHMARK = config["benchmark"]
# benchmark.compile_calls names first calls of the compiled kernels: checked by the
# kernel_cache job (accelcal_repro.first_calls.check_calls), so that parsing imports no
# reproduction.
TIMING_DIR = results("timing")
BENCHMARK_FIGURE = "timing_benchmark"
BENCHMARK_STAGE = declare_stage(
    name="benchmark",
    figures=(BENCHMARK_FIGURE,),
    claims=False,
    tables=(("Where the compute time goes: estimators at 24 poses, filters per step, first-call compilation "
             "and job-seconds per stage, with the project's goals", f"{TIMING_DIR}/summary.csv"),),
)


rule timing_filters:
    """Cost per step of the Batista filter and of Tereshkov's estimator, compiled and numpy.

    threads = all cores: Snakemake then runs it alone, so no other job perturbs the clock.
    """
    input:
        kernel_cache=KERNEL_CACHE,
    output:
        f"{TIMING_DIR}/filters.csv",
    params:
        # what the timed runs read (config per key: new claim thresholds do not rerun the timing)
        batista=config_keys(config["batista2011"], "seed", "g", "filter"),
        tereshkov=config_keys(config["tereshkov"], *TERESHKOV_RUNS),
        bench=BENCHMARK["tereshkov"],
    log:
        log_path("benchmark/filters"),
    benchmark:
        bench_path("benchmark/filters"),
    threads: workflow.cores
    resources:
        mem_mb=2000,
        runtime=20,
    script:
        "../scripts/timing_filters.py"


def _other_figures(wildcards):
    """Every figure but this target's: the stage table is read once every other job is done."""
    return [path for path in figure_files(*figure_ids()) if path.endswith(".png") and BENCHMARK_FIGURE not in path]


rule timing_stages:
    """Job-seconds per stage from results/benchmarks/ (every rule writes its file there),
    after every other figure and the ledger: the last run of each job."""
    localrule: True  # on a cluster: the login node (reads the benchmark files)
    input:
        figures=_other_figures,
        claims=results("claims.csv"),
    output:
        f"{TIMING_DIR}/stages.csv",
    params:
        benchmarks_dir=results("benchmarks"),
    log:
        log_path("benchmark/stages"),
    benchmark:
        bench_path("benchmark/stages"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/timing_stages.py"


rule timing_benchmark_figure:
    """The summary table (with the goals) and the figure."""
    localrule: True  # on a cluster: the login node (a table and a figure, last)
    input:
        estimators=results("burkhard2024/timing_summary.csv"),
        filters=f"{TIMING_DIR}/filters.csv",
        compile=f"{TIMING_DIR}/compile.csv",
        stages=f"{TIMING_DIR}/stages.csv",
    output:
        summary=f"{TIMING_DIR}/summary.csv",
        **figure_outputs(BENCHMARK_FIGURE, f"../report/{BENCHMARK_FIGURE}.rst", "Benchmark"),
    params:
        goals=BENCHMARK["goals"],
        n_poses=config["burkhard2024"]["timing"]["headline_n_poses"],
        interleave=config["burkhard2024"]["timing"]["headline_interleave"],
    log:
        log_path("benchmark/figure"),
    benchmark:
        bench_path("benchmark/figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/timing_benchmark.py"


rule benchmark:
    """Every output of the benchmark (target only)."""
    localrule: True
    input:
        f"{TIMING_DIR}/summary.csv",
        figure_files(BENCHMARK_FIGURE),
