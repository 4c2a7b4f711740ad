"""The compile job: every compiled kernel's first call once, writing the project's numba disk
cache, ahead of the jobs that call the kernels (each has KERNEL_CACHE as an input).

Without it the first jobs of a fresh clone each reach the same uncompiled kernels at once:
one compiles while the others hold their cores waiting for its lock (accelcal.kernels.njit).
The table lists the first-call times (compilation, or loading when the cache was already
full); it lives under results/timing/ with the other wall times (not reproducible).

Needs from common.smk: results, log_path, bench_path, KERNEL_CACHE.
"""


rule kernel_cache:
    """Fill the numba disk cache (first calls of accelcal_repro.first_calls, compiled)."""
    output:
        KERNEL_CACHE,
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
