"""Monte Carlo of the Burkhard setting at one noise level -> tidy CSV (one row per trial × method)."""

import time

from _helpers import configure_logging, mock_snakemake, write_csv

from accelcal.montecarlo import crlb_mc_point

if "snakemake" not in globals():
    from _helpers import load_config

    _cfg = load_config()
    _noise = _cfg["foundation"]["crlb"]["noise_std"][0]
    snakemake = mock_snakemake(
        "foundation_crlb_mc",
        output=[f"results/foundation/crlb_mc/noise_{format(float(_noise), '.12g')}.csv"],
        params={"seed": _cfg["seed"], "noise_std": _noise, "trials": _cfg["foundation"]["crlb"]["trials"],
                "methods": _cfg["foundation"]["crlb"]["methods"],
                "als_known_noise": _cfg["foundation"]["crlb"]["als_known_noise"], "burkhard": _cfg["burkhard"]},
    )

log = configure_logging(snakemake)
p = snakemake.params
bk = p.burkhard
t0 = time.perf_counter()
df = crlb_mc_point(
    seed=p.seed, noise_std=float(p.noise_std), trials=int(p.trials), n_poses=int(bk["n_poses"]), g=float(bk["g"]),
    methods=list(p.methods), truth_ranges={k: tuple(v) for k, v in bk["truth"].items()},
    als_known_noise=bool(p.als_known_noise),
)
log.info("noise %g: %d trials x %d methods in %.1f s; invalid per method: %s", p.noise_std, p.trials,
         len(p.methods), time.perf_counter() - t0, (~df["valid"]).groupby(df["method"]).sum().to_dict())
write_csv(df, snakemake.output[0])
