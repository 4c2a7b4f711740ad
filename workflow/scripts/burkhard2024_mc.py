"""Monte Carlo of one Burkhard grid point -> tidy table (one row per trial × case × method)
and the wall time of each method over the point's trials."""

import time

from _helpers import configure_logging, load_config, mock_snakemake_from_argv, write_csv

from accelcal import kernels
from accelcal_repro.montecarlo import mc_point

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    from _burkhard2024_points import grid_points

    _first = next(iter(grid_points(load_config()["burkhard2024"]["experiments"])))
    snakemake = mock_snakemake_from_argv("burkhard2024_mc", bk_point=_first)

log = configure_logging(snakemake)
p = snakemake.params
kernels.set_backend(p.kernels)
pt = p.point
t0 = time.perf_counter()
table, timing = mc_point(
    seed=int(p.seed), n_poses=int(pt["n_poses"]), noise_std=float(pt["noise_std"]), cases=pt["cases"],
    trials=int(p.trials), g=float(p.g), truth_ranges={k: tuple(v) for k, v in p.truth.items()},
    als_known_noise=bool(p.als_known_noise), nlls_known_noise=bool(p.nlls_known_noise),
)
invalid = (~table["valid"]).groupby([table["data_model"], table["g_error"], table["method"]]).sum()
log.info("%d poses, noise %g: %d cases x %d trials in %.1f s; invalid trials: %s", pt["n_poses"], pt["noise_std"],
         len(pt["cases"]), p.trials, time.perf_counter() - t0, invalid[invalid > 0].to_dict() or "none")
write_csv(table, snakemake.output.table, float_format="%.10g")
write_csv(timing, snakemake.output.timing)
