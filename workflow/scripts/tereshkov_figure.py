"""Figures of the Tereshkov stage: fig2 (heading), fig3 (gyro), fig4 (accelerometer),
installation (sweep), comparison (bias_convergence_comparison); which one is
``snakemake.params.figure``."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.plotting import save_figure
from accelcal_repro.tereshkov import figures

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_fig3_figure")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
est, cl = cfg["estimator"], cfg["claims"]
which = snakemake.params.figure
i = snakemake.input
n_ex = int(cfg.get("figures", {}).get("example_runs", 2))
if which == "fig2":
    fig = figures.plot_heading(pd.read_csv(i.headings), float(est["turn_rate_dps"]))
elif which == "fig3":
    fig = figures.plot_gyro(pd.read_csv(i.field), pd.read_csv(i.straight), pd.read_csv(i.summary),
                            example_runs=tuple(range(n_ex)), paper_conv_s=float(cl["gyro_convergence_s"]),
                            filter_s=float(est["gyro_filter_s"]))
elif which == "fig4":
    fig = figures.plot_accel(pd.read_csv(i.field), pd.read_csv(i.straight), pd.read_csv(i.artificial),
                             pd.read_csv(i.summary), example_run=0, paper_conv_s=float(cl["accel_convergence_s"]),
                             filter_s=float(est["accel_filter_s"]))
elif which == "installation":
    fig = figures.plot_installation(pd.read_csv(i.sweep), float(cl["gyro_ss_rms_dps"]), float(cl["accel_ss_rms_mps2"]),
                                    float(cl["installation_max_deg"]))
elif which == "comparison":
    fig = figures.plot_comparison(pd.read_csv(i.table), pd.read_csv(i.summary))
else:
    raise ValueError(f"unknown Tereshkov figure {which!r}")
for path in save_figure(fig, snakemake.output.png):
    log.info("wrote %s", path)
