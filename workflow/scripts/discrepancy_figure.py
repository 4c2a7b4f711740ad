"""The figures of the discrepancy stage (one script, the figure id in params)."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.discrepancy import figures as F
from accelcal_repro.discrepancy import figures as benchmark_figures
from accelcal.plotting import save_figure

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_power_figure")

log = configure_logging(snakemake)
fid = snakemake.params.figure
if fid == "discrepancy_confusion":
    scores = pd.read_csv(snakemake.input.scores, keep_default_na=False, na_values=[""])
    fig = benchmark_figures.plot_confusion(scores, snakemake.params.confusion_size, snakemake.params.rules["alpha"])
elif fid == "discrepancy_power":
    summ = pd.read_csv(snakemake.input.summary)
    fpr = summ[(summ.effect == "none") & (summ.metric == "false_positive_rate")]["value"]
    fig = benchmark_figures.plot_power(pd.read_csv(snakemake.input.rates), snakemake.params.rules["power"],
                       snakemake.params.rules["alpha"], float(fpr.iloc[0]) if len(fpr) else None)
else:
    reports = {}
    for name, path in zip(snakemake.params.recordings, snakemake.input.reports):
        with open(path) as f:
            reports[name] = json.load(f)
    if fid == "discrepancy_measured_before_after":
        fig = F.plot_before_after(reports)
    elif fid == "discrepancy_allan":
        missing = [n for n, r in reports.items() if r.get("stochastic") is None]
        if missing:
            raise SystemExit(f"no stochastic layer for {', '.join(missing)}: "
                             f"{'; '.join(reports[n].get('stochastic_error', '') for n in missing)}")
        fig = F.allan_figure({n: r["stochastic"] for n, r in reports.items()})
    else:
        raise SystemExit(f"unknown figure {fid!r}")
save_figure(fig, snakemake.output.png)
log.info("%s -> %s, %s", fid, snakemake.output.png, snakemake.output.pdf)
