"""Every magnetometer method on every configured session; the SNU session-to-session table."""

import numpy as np
import pandas as pd
from _helpers import configure_logging, dataset_dirs, mock_snakemake_from_argv, write_csv

from accelcal.summary import write_summaries
from accelcal_repro.mag.sessions import FILES
from accelcal_repro.mag.stage import session_rows, stability

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_sessions")

log = configure_logging(snakemake)
dirs = dataset_dirs(snakemake.input.manifests)
published = None
if "mag_qmc5883l_suarez" in dirs:
    published = np.loadtxt(dirs["mag_qmc5883l_suarez"] / "mag_qmc5883l_suarez" / "paramters_mag.csv")
rows, cals, summaries = [], {}, {}
for name in snakemake.params.mag["sessions"]:
    r, mc = session_rows(name, dirs[FILES[name][0]], published)
    rows += r
    summaries[name] = mc.summary()
    if name.startswith("snu_good"):
        cals[name] = mc
    for row in r:
        log.info("%s %s: |m| spread %.3f %%, dip spread %.3f deg", name, row["method"], row["norm_spread_pct"],
                 row["dip_spread_deg"])
write_csv(pd.DataFrame(rows), snakemake.output.table)
write_summaries(snakemake.output.summaries, summaries)
write_csv(stability(cals) if len(cals) > 1 else pd.DataFrame(columns=["parameter"]), snakemake.output.stability)
