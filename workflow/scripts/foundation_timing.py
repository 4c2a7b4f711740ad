"""Benchmark: LLS vs NLLS per-problem wall time (interleaved, one run) and batched throughput."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal.timing import run_benchmark, summarize_timing

if "snakemake" not in globals():
    from _helpers import load_config

    _cfg = load_config()
    snakemake = mock_snakemake(
        "foundation_timing_run",
        output={"single": "results/foundation/timing.csv", "batch": "results/foundation/timing_batch.csv",
                "summary": "results/foundation/timing_summary.csv"},
        params={"seed": _cfg["seed"], "timing": _cfg["foundation"]["timing"], "g": _cfg["burkhard"]["g"],
                "n_poses": _cfg["burkhard"]["n_poses"]},
    )

log = configure_logging(snakemake)
t = snakemake.params.timing
single, batch = run_benchmark(
    seed=snakemake.params.seed, g=float(snakemake.params.g), noise_std=float(t["noise_std"]),
    n_problems=int(t["problems"]), n_poses=int(snakemake.params.n_poses), repeats=int(t["repeats"]),
    batch_problems=int(t["batch_problems"]), batch_repeats=int(t["batch_repeats"]),
    interleavings=list(t["interleavings"]),
)
summary = summarize_timing(single, batch)
with pd.option_context("display.width", 250, "display.max_columns", 20, "display.float_format", "{:.4g}".format):
    log.info("timing summary (wall times are machine-dependent; recorded, not asserted):\n%s", summary)
write_csv(single, snakemake.output.single)
write_csv(batch, snakemake.output.batch)
write_csv(summary, snakemake.output.summary)
