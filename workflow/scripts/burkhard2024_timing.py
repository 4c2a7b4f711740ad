"""Benchmark: per-problem wall time of every method side by side (interleaved, one run) at
each pose count, compiled kernels and numpy reference, and the batched closed forms'
throughput."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.timing import available_backends, run_benchmark, summarize_timing

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("burkhard2024_timing_run")

log = configure_logging(snakemake)
p = snakemake.params
t = p.timing
single, batch = run_benchmark(
    seed=int(p.seed), g=float(p.g), noise_std=float(t["noise_std"]), n_poses=[int(n) for n in t["n_poses"]],
    n_problems=int(t["problems"]), repeats=int(t["repeats"]), batch_problems=int(t["batch_problems"]),
    batch_repeats={"numpy": int(t["batch_repeats"]), "numba": int(t["batch_repeats_compiled"])},
    interleavings=list(t["interleavings"]),
    als_known_noise=bool(p.als_known_noise), nlls_known_noise=bool(p.nlls_known_noise),
    backends=[b for b in t["backends"] if b in available_backends()],
)
summary = summarize_timing(single, batch)
failed = single[single["status"] != "ok"]
if len(failed):
    log.warning("failed solves (timed anyway): %s", failed.groupby(["n_poses", "method", "status"]).size().to_dict())
with pd.option_context("display.width", 250, "display.max_columns", 20, "display.float_format", "{:.4g}".format):
    log.info("timing summary (wall times are machine-dependent; recorded, not asserted):\n%s", summary)
write_csv(single, snakemake.output.single)
write_csv(batch, snakemake.output.batch)
write_csv(summary, snakemake.output.summary)
