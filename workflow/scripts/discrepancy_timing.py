"""Job-seconds of the discrepancy benchmark from the jobs' benchmark files (wall s and CPU s)."""

import os
from pathlib import Path

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_timing")

log = configure_logging(snakemake)
rows = []
for path in [*snakemake.input.chunks, *snakemake.input.other]:
    b = pd.read_csv(path, sep="\t")
    job = Path(path).stem
    rows.append({"job": job, "kind": "chunk" if job.startswith("chunk_") else ("figure" if job == "figures" else job),
                 "wall_s": float(b["s"].iloc[-1]),
                 "cpu_s": float(b["cpu_time"].iloc[-1]), "max_rss_mb": float(b["max_rss"].iloc[-1]),
                 "mean_load": float(b["mean_load"].iloc[-1])})
df = pd.DataFrame(rows)
load = os.getloadavg()
total = pd.DataFrame([{"job": "total", "kind": "total", "wall_s": df.wall_s.sum(), "cpu_s": df.cpu_s.sum(),
                       "max_rss_mb": df.max_rss_mb.max(), "mean_load": float("nan")}])
out = pd.concat([df, total], ignore_index=True)
out["chunks"] = snakemake.params.chunks
out["loadavg_1min_at_gather"] = load[0]
out["cpus"] = os.cpu_count()
write_csv(out, snakemake.output[0])
log.info("benchmark job-seconds: wall %.1f s, cpu %.1f s over %d jobs (%d chunks, chunk wall max %.1f s); "
         "load average now %.2f on %d CPUs", total.wall_s[0], total.cpu_s[0], len(df), snakemake.params.chunks,
         df[df.kind == "chunk"].wall_s.max(), load[0], os.cpu_count())
