"""results/discrepancy/summary.csv (benchmark scores + what the loop finds on the real recordings)
and results/discrepancy/measured.csv (every candidate test on the real recordings)."""

import json

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_summary")

log = configure_logging(snakemake)
COLUMNS = ["section", "null", "profile", "recording", "effect", "metric", "value", "ci_low", "ci_high", "n",
           "n_independent", "target", "verdict", "rule"]
bench = pd.read_csv(snakemake.input.benchmark, keep_default_na=False, na_values=[""])
bench.insert(3, "recording", "")
measured_stage = pd.read_csv(snakemake.input.measured_summary)

rows, cand_rows = [], []
for name, path in zip(snakemake.params.recordings, snakemake.input.reports):
    with open(path) as f:
        rep = json.load(f)

    def row(metric, value, effect=rep["effect"], verdict="", rule="", target=np.nan):
        rows.append({"section": "measured", "null": "", "profile": "", "recording": name, "effect": effect,
                     "metric": metric, "value": np.nan if value is None else value, "ci_low": np.nan,
                     "ci_high": np.nan, "n": rep["n_poses"], "n_independent": np.nan, "target": target,
                     "verdict": verdict, "rule": rule})

    named = "+".join(rep["effects"]) or "none"
    row("outcome", np.nan, verdict=rep["outcome"],
        rule=f"effects named in order: {named}; not identifiable: {', '.join(rep['not_identifiable']) or '-'}")
    for k in ("gap_before", "gap_after", "gap_expected_before", "gap_expected_after", "gap_lopo_before",
              "gap_lopo_after", "excess_before", "excess_after", "excess_explained_fraction"):
        row(k, rep[k], rule="RMS pose residual / its noise (noise alone: gap_expected)" if k.startswith("gap") else "")
    # The residual excess of the measured stage (full NLLS: the same model as the base here).
    ms = measured_stage[(measured_stage.recording == name) & (measured_stage.estimator == "full_nlls")]
    if len(ms):
        row("measured_stage_excess", float(ms.excess.iloc[0]),
            rule="results/measured/summary.csv, full_nlls: sqrt(chi2/dof) of the residuals against the pose noise")
    row("excess_status", np.nan, verdict=rep["excess_status"],
        rule="chi2 of the residuals against the pose noise at level alpha: 'no excess' (base model consistent), "
             "'explained' (consistent after the named effects), 'not explained'")
    imp = rep.get("noise_implication") or {}
    if imp:
        row("noise_expected_excess", imp["expected_excess"], effect="+".join(sorted({t for v in imp["named_terms"].values()
                                                                                      for t in v})),
            verdict=imp["verdict"],
            rule=f"residual excess the named noise terms predict (observed {imp['observed_excess']:.3g}); "
                 f"two-sided chi2 p = {imp['p_value']:.3g}; explained: {'yes' if imp['explains_excess'] else 'no'}")
        row("noise_expected_excess_short_term", imp["expected_excess_short_term"], effect="",
            rule="same, each pose mean carrying only the extra Allan variance at its own duration (no wander "
                 "between poses)")
    st = rep.get("stochastic")
    if st:
        for ax, a in st["axes"].items():
            terms = "+".join(a["named"])
            row(f"allan_gap_before_{ax}", a["gap_before"], effect=terms, rule="RMS standardised log10 ADEV ratio, "
                "measured vs white-only simulation")
            row(f"allan_gap_after_{ax}", a["gap_after"], effect=terms, rule="same, after adding the named terms")
    else:
        row("stochastic_layer", np.nan, verdict="not run", rule=rep.get("stochastic_error", ""))
    for c in rep["candidates"]:
        d = {"recording": name, **{k: v for k, v in c.items() if not isinstance(v, list)}}
        for k in ("mde", "mde_data", "absorbed_axis", "estimate", "se", "se_noise", "parameters"):
            for a, v in zip("xyz", c[k]):
                d[f"{k}_{a}"] = v
        d["reasons"] = "; ".join(c["reasons"])
        d["dof"] = f"{c['dof'][0]},{c['dof'][1]}"
        cand_rows.append(d)
        if c["round"] == 1 and not c["identifiable"]:
            row("not_identifiable", c["absorbed"], effect=c["effect"], verdict="not identifiable",
                rule="value = absorbed fraction; " + "; ".join(c["reasons"]))

summary = pd.concat([bench[COLUMNS], pd.DataFrame(rows, columns=COLUMNS)], ignore_index=True)
write_csv(summary, snakemake.output.summary)
write_csv(pd.DataFrame(cand_rows), snakemake.output.candidates)
log.info("summary: %d rows; measured candidates: %d rows", len(summary), len(cand_rows))
