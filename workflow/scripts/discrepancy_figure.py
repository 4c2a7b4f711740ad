"""The figures of the discrepancy stage, drawn in one job (common.smk's stage_figures)."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, stage_figures

from accelcal.discrepancy import figures as F
from accelcal.plotting import save_figure
from accelcal_repro.discrepancy import figures as BF

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_figures")

log = configure_logging(snakemake)
p = snakemake.params


def table(path):
    return pd.read_csv(path, keep_default_na=False, na_values=[""])


def reports(inp):
    out = {}
    for name, path in zip(p.recordings, inp.reports):
        with open(path) as f:
            out[name] = json.load(f)
    return out


def draw(fid, inp):
    if fid == "discrepancy_fpr":
        return BF.plot_fpr(table(inp.summary), table(inp.profiles), p.rules["alpha"], p.profiles)
    if fid == "discrepancy_confusion":
        return BF.plot_confusion(table(inp.scores), p.confusion_size, p.profiles)
    if fid == "discrepancy_power":
        return BF.plot_power(table(inp.rates), p.rules["power"], p.profiles, p.curve_profiles, p.sizes)
    if fid == "discrepancy_rows":
        return BF.plot_rows(table(inp.rates), p.profiles)
    if fid == "discrepancy_adis_allan":
        return BF.plot_adis_allan(table(inp.curves), table(inp.allan), table(inp.check))
    if fid == "discrepancy_sessions":
        sims = {n: pd.read_csv(f) for n, f in zip(p.recordings, inp.sims)}
        return BF.plot_sessions(reports(inp), sims, table(inp.gaps))
    if fid == "discrepancy_evidence":
        return BF.plot_evidence(table(inp.evidence), reports(inp))
    if fid == "discrepancy_stability":
        return BF.plot_stability(table(inp.stability), table(inp.estimates))
    if fid == "discrepancy_measured_before_after":
        return F.plot_before_after(reports(inp))
    if fid == "discrepancy_allan":
        reps = reports(inp)
        missing = [n for n, r in reps.items() if r.get("stochastic") is None]
        if missing:
            raise SystemExit(f"no stochastic layer for {', '.join(missing)}: "
                             f"{'; '.join(reps[n].get('stochastic_error', '') for n in missing)}")
        return F.allan_figure({n: r["stochastic"] for n, r in reps.items()})
    raise SystemExit(f"unknown figure {fid!r}")


for fid, inp, out in stage_figures(snakemake):
    save_figure(draw(fid, inp), out.png)
    log.info("%s -> %s, %s", fid, out.png, out.pdf)
