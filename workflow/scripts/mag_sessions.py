"""Every magnetometer method on every configured session; the SNU session-to-session table."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.mag.sessions import FILES
from accelcal_repro.mag.stage import session_rows, stability

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("mag_sessions")

log = configure_logging(snakemake)
# every dataset's files sit in <dir>/<dataset>/ (the shared copy or the verified download)
dirs = {}
for path in snakemake.input.manifests:
    m = json.loads(Path(path).read_text())
    first = next(iter(m["files"].values()))["path"]
    dirs[m["dataset"]] = Path(first).parent.parent
published = None
if "mag_qmc5883l_suarez" in dirs:
    published = np.loadtxt(dirs["mag_qmc5883l_suarez"] / "mag_qmc5883l_suarez" / "paramters_mag.csv")
rows, cals = [], {}
for name in snakemake.params.mag["sessions"]:
    r, mc = session_rows(name, dirs[FILES[name][0]], published)
    rows += r
    if name.startswith("snu_good"):
        cals[name] = mc
    for row in r:
        log.info("%s %s: |m| spread %.3f %%, dip spread %.3f deg", name, row["method"], row["norm_spread_pct"],
                 row["dip_spread_deg"])
write_csv(pd.DataFrame(rows), snakemake.output.table)
write_csv(stability(cals) if len(cals) > 1 else pd.DataFrame(columns=["parameter"]), snakemake.output.stability)
