"""The benchmark's noise profiles resolved to counts, and what each does to the session's pose means."""

import json

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal.atomic import write_json_atomic
from accelcal_repro.discrepancy import adis as A
from accelcal_repro.discrepancy import profiles as P
from accelcal_repro.discrepancy.benchmark import Session

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("discrepancy_profiles")

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
profiles = P.build_profiles(bench["profiles"], session, fitted=fitted)
write_json_atomic(snakemake.output.profiles, {n: p.to_dict() for n, p in profiles.items()})
table = pd.DataFrame(P.profile_table(profiles, session))
write_csv(table, snakemake.output.table)
for name, d in table.groupby("profile", sort=False):
    log.info("%s (%s): %s; pose-mean wander / white noise %s", name, d.kind.iloc[0], d.terms.iloc[0],
             ", ".join(f"{v:.2f}" for v in d.wander_over_white))
