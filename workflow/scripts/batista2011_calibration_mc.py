"""One chunk of the Table I Monte Carlo (with the linear-only variant and the full LLS):
the runs ``params.runs = [first, stop)``, each from its own random stream."""

import time

from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.batista2011.experiment import design_from_config
from accelcal_repro.batista2011.montecarlo import calibration_montecarlo, run_streams

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("batista2011_calibration_mc", chunk="0")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
c = cfg["calibration"]
first, stop = (int(x) for x in snakemake.params.runs)
design = design_from_config(cfg)
log.info("design: %d steps x %d samples, Tg = %s; runs %d-%d", len(design.euler),
         design.schedule.samples_per_window, design.g_table.round(4).tolist(), first, stop - 1)
t0 = time.perf_counter()
ids = range(first, stop)
errors = calibration_montecarlo(design, run_streams(cfg["seed"], "calibration", ids), tol=float(c["tol"]),
                                max_iter=int(c["max_iter"]), chunk=int(c["chunk"]), run_ids=ids)
log.info("%d runs in %.1f s", len(ids), time.perf_counter() - t0)
# lossless: the merge computes the summaries from these numbers
write_csv(errors, snakemake.output[0], float_format="%.17g")
