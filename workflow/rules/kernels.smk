"""The compile job: every compiled kernel's first call once, writing the project's numba disk
cache, ahead of the jobs that call the kernels (each has KERNEL_CACHE as an input), and the
benchmark's first-call times (results/timing/compile.csv) from the same compilation.

Without it the first jobs of a fresh clone each reach the same uncompiled kernels at once:
one compiles while the others hold their cores waiting for its lock (accelcal.kernels.jit).
Timing the compilation needs an empty cache, so the first calls run in a fresh process with
an empty cache folder of its own; with `benchmark.compile_calls: all` that process compiles
every kernel, and its cache is copied into the project's: one compilation where a separate
timing job compiled everything a second time (24 s of CPU in a fresh clone, 780f7f0).
The tables list the first-call times; they live under results/timing/ with the other wall
times (not reproducible).

Needs from common.smk: results, log_path, bench_path, KERNEL_CACHE.
"""


rule kernel_cache:
    """Fill the numba disk cache (first calls of accelcal_repro.first_calls, compiled) and time them."""
    output:
        cache=KERNEL_CACHE,
        compile=results("timing/compile.csv"),
    params:
        # a workflow without the benchmark stage (a stage run alone) fills the cache with every kernel
        calls=config.get("benchmark", {}).get("compile_calls", "all"),
    log:
        log_path("benchmark/kernel_cache"),
    benchmark:
        bench_path("benchmark/kernel_cache"),
    priority: 90  # right after a download (100): a failing fetch still stops the run first
    localrule: True  # on a cluster: the login node fills the cache on the shared disk once
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,
    script:
        "../scripts/kernel_cache.py"
