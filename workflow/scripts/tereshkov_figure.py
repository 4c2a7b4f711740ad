"""Figures of the Tereshkov stage: fig2 (heading), fig3 (gyro), fig4 (accelerometer),
installation (sweep), comparison (bias_convergence_comparison); which one is
``snakemake.params.figure``."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake
from tereshkov_common import stage_config

from accelcal.plotting import save_figure
from accelcal_repro.tereshkov import figures

if "snakemake" not in globals():
    import sys

    _fig = sys.argv[1] if len(sys.argv) > 1 else "fig3"
    _d = "results/tereshkov"
    _inputs = {
        "fig2": {"headings": f"{_d}/headings.csv"},
        "fig3": {"field": f"{_d}/field.csv.gz", "straight": f"{_d}/straight.csv.gz", "summary": f"{_d}/summary.csv"},
        "fig4": {"field": f"{_d}/field.csv.gz", "straight": f"{_d}/straight.csv.gz",
                 "artificial": f"{_d}/artificial.csv.gz", "summary": f"{_d}/summary.csv"},
        "installation": {"sweep": f"{_d}/sweep_summary.csv"},
        "comparison": {"table": f"{_d}/comparison.csv.gz", "summary": f"{_d}/comparison_summary.csv"},
    }[_fig]
    _id = {"installation": "tereshkov_installation", "comparison": "bias_convergence_comparison"}.get(
        _fig, f"tereshkov_{_fig}")
    snakemake = mock_snakemake(f"tereshkov_{_fig}_figure", input=_inputs,
                               output={"png": f"results/figures/{_id}.png", "pdf": f"results/figures/{_id}.pdf"},
                               params={"figure": _fig, "cfg": stage_config()})

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
