"""The figures of the discrepancy stage (one script, the figure id in params)."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv

from accelcal.discrepancy import figures as F
from accelcal.plotting import save_figure
from accelcal_repro.discrepancy import figures as BF

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_fpr_figure")

log = configure_logging(snakemake)
fid = snakemake.params.figure
inp = snakemake.input
p = snakemake.params


def table(path):
    return pd.read_csv(path, keep_default_na=False, na_values=[""])


def reports():
    out = {}
    for name, path in zip(p.recordings, inp.reports):
        with open(path) as f:
            out[name] = json.load(f)
    return out


if fid == "discrepancy_fpr":
    fig = BF.plot_fpr(table(inp.summary), table(inp.profiles), p.rules["alpha"], p.profiles)
elif fid == "discrepancy_confusion":
    fig = BF.plot_confusion(table(inp.scores), p.confusion_size, p.profiles)
elif fid == "discrepancy_power":
    fig = BF.plot_power(table(inp.rates), p.rules["power"], p.profiles, p.curve_profiles, p.sizes)
elif fid == "discrepancy_rows":
    fig = BF.plot_rows(table(inp.rates), p.profiles)
elif fid == "discrepancy_adis_allan":
    fig = BF.plot_adis_allan(table(inp.curves), table(inp.allan), table(inp.check))
elif fid == "discrepancy_sessions":
    sims = {n: pd.read_csv(f) for n, f in zip(p.recordings, inp.sims)}
    fig = BF.plot_sessions(reports(), sims, table(inp.gaps))
elif fid == "discrepancy_evidence":
    fig = BF.plot_evidence(table(inp.evidence), reports())
elif fid == "discrepancy_stability":
    fig = BF.plot_stability(table(inp.stability), table(inp.estimates))
elif fid == "discrepancy_measured_before_after":
    fig = F.plot_before_after(reports())
elif fid == "discrepancy_allan":
    reps = reports()
    missing = [n for n, r in reps.items() if r.get("stochastic") is None]
    if missing:
        raise SystemExit(f"no stochastic layer for {', '.join(missing)}: "
                         f"{'; '.join(reps[n].get('stochastic_error', '') for n in missing)}")
    fig = F.allan_figure({n: r["stochastic"] for n, r in reps.items()})
else:
    raise SystemExit(f"unknown figure {fid!r}")
save_figure(fig, snakemake.output.png)
log.info("%s -> %s, %s", fid, snakemake.output.png, snakemake.output.pdf)
