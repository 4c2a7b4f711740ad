"""Figures of the Tereshkov stage, drawn in one job (common.smk's stage_figures):
tereshkov_fig2 (heading), tereshkov_fig3 (gyro), tereshkov_fig4 (accelerometer),
tereshkov_installation (sweep), bias_convergence_comparison (against Batista's filter)."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, stage_figures

from accelcal.plotting import save_figure
from accelcal_repro.tereshkov import figures

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("tereshkov_figures")

log = configure_logging(snakemake)
cfg = snakemake.params.cfg
est, cl = cfg["estimator"], cfg["claims"]
n_ex = int(cfg.get("figures", {}).get("example_runs", 2))


def draw(fid, i):
    if fid == "tereshkov_fig2":
        return figures.plot_heading(pd.read_csv(i.headings), float(est["turn_rate_dps"]))
    if fid == "tereshkov_fig3":
        return figures.plot_gyro(pd.read_csv(i.field), pd.read_csv(i.straight), pd.read_csv(i.summary),
                                 example_runs=tuple(range(n_ex)), paper_conv_s=float(cl["gyro_convergence_s"]),
                                 filter_s=float(est["gyro_filter_s"]))
    if fid == "tereshkov_fig4":
        return figures.plot_accel(pd.read_csv(i.field), pd.read_csv(i.straight), pd.read_csv(i.artificial),
                                  pd.read_csv(i.summary), example_run=0,
                                  paper_conv_s=float(cl["accel_convergence_s"]), filter_s=float(est["accel_filter_s"]))
    if fid == "tereshkov_installation":
        return figures.plot_installation(pd.read_csv(i.sweep), float(cl["gyro_ss_rms_dps"]),
                                         float(cl["accel_ss_rms_mps2"]), float(cl["installation_max_deg"]))
    if fid == "bias_convergence_comparison":
        return figures.plot_comparison(pd.read_csv(i.table), pd.read_csv(i.summary))
    raise ValueError(f"unknown Tereshkov figure {fid!r}")


for fid, inp, out in stage_figures(snakemake):
    for path in save_figure(draw(fid, inp), out.png):
        log.info("wrote %s", path)
