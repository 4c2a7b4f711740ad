"""Monte Carlo of one Burkhard grid point -> tidy table (one row per trial × case × method)
and the wall time of each method over the point's trials."""

import time

from _helpers import configure_logging, mock_snakemake, stage_config, write_csv

from accelcal_repro.montecarlo import mc_point

if "snakemake" not in globals():
    import sys

    from accelcal_repro.burkhard2024.grid import experiments_from_config, grid_points

    _cfg = stage_config("burkhard2024")
    _points = grid_points(experiments_from_config(_cfg["experiments"]))
    _key = sys.argv[1] if len(sys.argv) > 1 else next(iter(_points))
    snakemake = mock_snakemake(
        "burkhard2024_mc",
        output={"table": f"results/burkhard2024/mc/{_key}.csv.gz", "timing": f"results/burkhard2024/mc_timing/{_key}.csv"},
        params={"point": _points[_key], "seed": _cfg["seed"], "g": _cfg["g"], "truth": _cfg["truth"],
                "trials": _cfg["trials"], "als_known_noise": _cfg["als_known_noise"]},
        wildcards={"bk_point": _key},
    )

log = configure_logging(snakemake)
p = snakemake.params
pt = p.point
t0 = time.perf_counter()
table, timing = mc_point(
    seed=int(p.seed), n_poses=int(pt["n_poses"]), noise_std=float(pt["noise_std"]), cases=pt["cases"],
    trials=int(p.trials), g=float(p.g), truth_ranges={k: tuple(v) for k, v in p.truth.items()},
    als_known_noise=bool(p.als_known_noise),
)
invalid = (~table["valid"]).groupby([table["data_model"], table["g_error"], table["method"]]).sum()
log.info("%d poses, noise %g: %d cases x %d trials in %.1f s; invalid trials: %s", pt["n_poses"], pt["noise_std"],
         len(pt["cases"]), p.trials, time.perf_counter() - t0, invalid[invalid > 0].to_dict() or "none")
write_csv(table, snakemake.output.table, float_format="%.10g")
write_csv(timing, snakemake.output.timing)
