"""imucal's Ferraris calibration on its example session, against accelcal on the same poses."""

import pandas as pd
from _helpers import configure_logging, mock_snakemake_from_argv, write_csv

from accelcal_repro.measured.peer import ferraris_comparison
from accelcal_repro.measured.sources import FERRARIS_STATIC, read_manifest

if "snakemake" not in globals():  # standalone run: see _helpers.mock_snakemake_from_argv
    snakemake = mock_snakemake_from_argv("measured_peer")

log = configure_logging(snakemake)
paths = read_manifest(snakemake.input.manifest)
poses = pd.read_csv(snakemake.input.poses).set_index("label")
detected = {k: (int(poses.loc[k, "start_index"]), int(poses.loc[k, "stop_index"]))
            for k in FERRARIS_STATIC if k in poses.index}
df = ferraris_comparison(paths["example_ferraris_session.csv"], paths["example_ferraris_session_list.json"],
                         grav=float(snakemake.params.grav),
                         detected=detected if len(detected) == len(FERRARIS_STATIC) else None)
for r in df[df.tool == "accelcal"].itertuples():
    log.info("%s %s (%s, %s poses): %.6g, minus imucal %.2g %s", r.parameter, r.axis, r.method, r.poses, r.value,
             r.diff_to_imucal, r.unit)
write_csv(df, snakemake.output[0])
