"""The benchmark's noise profiles resolved to counts, what each does to the session's pose means, and the
transients the screen finds in the real record (the windows it leaves out)."""

import json

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.atomic import write_json_atomic
from accelcal_repro.discrepancy import adis as A
from accelcal_repro.discrepancy import profiles as P
from accelcal_repro.discrepancy import record_screen as RS
from accelcal_repro.discrepancy.benchmark import Session

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_profiles")


def screen_table(records: dict, fitted: dict, n: int, screen) -> pd.DataFrame:
    """One row per transient the screen finds in each real record: where, how large, which window it removes."""
    rows = []
    for name, rec in records.items():
        fs = float(fitted[name]["fs"])
        events = RS.transient_scan(rec, fs, screen)
        for ev in events:
            rows.append({"record": name, "axis": "xyz"[ev["axis"]], "block_s": ev["block_s"], "kind": ev["kind"],
                         "t_start_s": ev["start"] / fs, "t_stop_s": ev["stop"] / fs, "z": ev["z"],
                         "deviation": ev["deviation"], "window": ev["start"] // n,
                         "window_last": (ev["stop"] - 1) // n})
        w = RS.record_windows(len(rec), n)
        kept = RS.clean_windows(len(rec), n, events)
        log.info("record screen of %s: %d flagged runs of blocks, %d of %d windows of %d samples left out (%s)",
                 name, len(events), w - len(kept), w, n, ", ".join(str(k) for k in range(w) if k not in kept) or "none")
    return pd.DataFrame(rows, columns=["record", "axis", "block_s", "kind", "t_start_s", "t_stop_s", "z", "deviation",
                                       "window", "window_last"])


log = configure_logging(snakemake)
bench = snakemake.params.benchmark
session = Session.from_config(bench["session"])
fitted = {"adis16405": A.reference_profile_source(pd.read_csv(snakemake.input.models), session.rate)}
if snakemake.input.xsens:
    with open(snakemake.input.xsens[0]) as f:
        xsens = json.load(f)
    wanted = {p.get("fitted") for p in bench["profiles"]}
    if "xsens_mti" in wanted:
        fitted["xsens_mti"] = P.xsens_source(xsens)
    if "xsens_mti_joint" in wanted:
        fitted["xsens_mti_joint"] = P.joint_source(xsens, "xsens_mti")
records = {"adis16405": np.load(snakemake.input.record[0]).astype(float)} if snakemake.input.record else {}
screen = RS.RecordScreen.from_config(bench["record_screen"])
profiles = P.build_profiles(bench["profiles"], session, fitted=fitted, records=records, screen=screen)
write_json_atomic(snakemake.output.profiles, {n: p.to_dict() for n, p in profiles.items()})
write_csv(screen_table(records, fitted, session.n_samples, screen), snakemake.output.screen)
table = pd.DataFrame(P.profile_table(profiles, session))
write_csv(table, snakemake.output.table)
for name, d in table.groupby("profile", sort=False):
    log.info("%s (%s): %s; pose-mean wander / white noise %s", name, d.kind.iloc[0], d.terms.iloc[0],
             ", ".join(f"{v:.2f}" for v in d.wander_over_white))
