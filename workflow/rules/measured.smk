"""Stage 'measured' (issue 6): public real-IMU recordings, calibrated with every estimator
their pose count allows and evaluated without ground truth (noise-predicted χ²,
leave-one-pose-out, bootstrap over poses, agreement, nominal sensitivities, and imucal's
Ferraris calibration as a peer).  Config: the `measured` mapping
(section `measured` of config/config.yaml).

Needs from common.smk: FIGURES, CLAIM_STAGES, log_path, figure_outputs, SMALL.
"""

import os
import re

from snakemake.exceptions import WorkflowError

from accelcal_repro.measured.data import DatasetError
from accelcal_repro.measured.sources import check_source_available

FIGURES.extend(["measured_static_detection", "measured_calibration", "measured_residuals"])
CLAIM_STAGES.append("measured")

MEASURED = config["measured"]
MEASURED_RECORDINGS = list(MEASURED["recordings"])
#: A relative data_dir is taken from the project root (the Snakefile's folder), so that
#: `--directory elsewhere` (the tests) still finds ../shared/data.
MEASURED_DATA_DIR = os.path.normpath(os.path.join(workflow.basedir, MEASURED["data_dir"]))
MEASURED_TABLES = ("poses", "params", "pose_errors", "summary", "agreement", "nominal")
#: The peer runs on the imucal session only if that recording is configured.
MEASURED_PEER = ["results/measured/peer_imucal.csv"] if "imucal_ferraris" in MEASURED_RECORDINGS else []
REPORT_TABLES.extend([
    ("measured", "Fit quality per recording and estimator (χ², leave-one-pose-out, bootstrap)",
     "results/measured/summary.csv"),
    ("measured", "Sensitivities against the data sheet", "results/measured/nominal.csv"),
] + [("measured", "imucal's Ferraris calibration against accelcal", p) for p in MEASURED_PEER])


class MeasuredDataError(WorkflowError):
    """A configured recording that is not local and cannot be downloaded (one line)."""


def check_measured_data(recordings, data_dir, resources_dir):
    """Fail before any job runs if a recording is in neither data_dir nor the download
    cache and its URL does not answer (accelcal_repro.measured.sources.check_source_available:
    the network is asked only for a file that is not local, with a short timeout)."""
    try:
        for name in recordings:
            check_source_available(name, data_dir, resources_dir)
    except DatasetError as e:
        raise MeasuredDataError(f"missing measured data: {e}") from None


check_measured_data(MEASURED_RECORDINGS, MEASURED_DATA_DIR, MEASURED["resources_dir"])


wildcard_constraints:
    recording="|".join(re.escape(r) for r in MEASURED_RECORDINGS),


rule measured_fetch:
    """Locate (shared copy) or download and verify (sha256) every file of one recording;
    the manifest records which path was used.  No data file enters the repository.
    High priority: when a download is needed it runs first, before the long Monte Carlo
    jobs, so that a failing download stops the run early."""
    priority: 100
    localrule: True  # on a cluster: the login node (internet access; a checksum when the data is local)
    output:
        "results/measured/data/{recording}.json",
    params:
        data_dir=MEASURED_DATA_DIR,
        resources_dir=MEASURED["resources_dir"],
    log:
        log_path("measured/fetch_{recording}"),
    benchmark:
        bench_path("measured/fetch_{recording}"),
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,  # a download of at most 3.3 MB
    script:
        "../scripts/measured_fetch.py"


rule measured_convert:
    """The recording in the canonical CSV of the CLI (t,ax,ay,az; file units)."""
    input:
        manifest="results/measured/data/{recording}.json",
    output:
        "results/measured/{recording}.csv",
    log:
        log_path("measured/convert_{recording}"),
    benchmark:
        bench_path("measured/convert_{recording}"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_convert.py"


rule measured_calibrate:
    """Static detection, every configured estimator, χ², leave-one-pose-out, bootstrap; on
    the original file, read with the readers of `accelcal calibrate`."""
    input:
        manifest="results/measured/data/{recording}.json",
    output:
        **{t: f"results/measured/{{recording}}/{t}.csv" for t in MEASURED_TABLES},
    params:
        settings=lambda w: MEASURED["recordings"][w.recording],
        bootstrap=MEASURED["bootstrap"],
        static=MEASURED["static"],
    log:
        log_path("measured/calibrate_{recording}"),
    benchmark:
        bench_path("measured/calibrate_{recording}"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=15,  # Xsens, 1000 replicates: about 30 s (full NLLS ~20 ms per replicate)
    script:
        "../scripts/measured_calibrate.py"


rule measured_peer:
    """imucal's Ferraris calibration on its example session against accelcal's bias-only
    estimators, on the section list's poses and on accelcal's detected rests."""
    input:
        manifest="results/measured/data/imucal_ferraris.json",
        poses="results/measured/imucal_ferraris/poses.csv",
    output:
        "results/measured/peer_imucal.csv",
    params:
        grav=lambda w: MEASURED["recordings"]["imucal_ferraris"]["g"],
        rate_hz=MEASURED["peer"]["rate_hz"],
    log:
        log_path("measured/peer_imucal"),
    benchmark:
        bench_path("measured/peer_imucal"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_peer.py"


rule measured_tables:
    """Gather the per-recording tables: results/measured/<table>.csv."""
    input:
        **{t: expand("results/measured/{recording}/{t}.csv", recording=MEASURED_RECORDINGS, t=[t])
           for t in MEASURED_TABLES},
    output:
        **{t: f"results/measured/{t}.csv" for t in MEASURED_TABLES},
    log:
        log_path("measured/tables"),
    benchmark:
        bench_path("measured/tables"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_tables.py"


rule measured_claims:
    """Ledger rows for the papers' real-data results (not reproducible: no public data)."""
    input:
        summary="results/measured/summary.csv",
        params="results/measured/params.csv",
        nominal="results/measured/nominal.csv",
        peer=MEASURED_PEER,
    output:
        "results/claims/measured.csv",
    log:
        log_path("measured/claims"),
    benchmark:
        bench_path("measured/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_claims.py"


rule measured_static_detection_figure:
    input:
        csv=expand("results/measured/{recording}.csv", recording=MEASURED_RECORDINGS),
        poses="results/measured/poses.csv",
    output:
        **figure_outputs("measured_static_detection", "../report/measured_static_detection.rst", "Measured data"),
    params:
        figure="measured_static_detection",
        recordings=MEASURED_RECORDINGS,
    log:
        log_path("measured/static_detection_figure"),
    benchmark:
        bench_path("measured/static_detection_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_figure.py"


rule measured_calibration_figure:
    input:
        params="results/measured/params.csv",
        peer=MEASURED_PEER,
    output:
        **figure_outputs("measured_calibration", "../report/measured_calibration.rst", "Measured data"),
    params:
        figure="measured_calibration",
        recordings=MEASURED_RECORDINGS,
    log:
        log_path("measured/calibration_figure"),
    benchmark:
        bench_path("measured/calibration_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_figure.py"


rule measured_residuals_figure:
    input:
        pose_errors="results/measured/pose_errors.csv",
    output:
        **figure_outputs("measured_residuals", "../report/measured_residuals.rst", "Measured data"),
    params:
        figure="measured_residuals",
        recordings=MEASURED_RECORDINGS,
    log:
        log_path("measured/residuals_figure"),
    benchmark:
        bench_path("measured/residuals_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_figure.py"


# Figure ids as targets: `snakemake measured_calibration`.
rule measured_static_detection:
    input:
        "results/figures/measured_static_detection.png",
        "results/figures/measured_static_detection.pdf",


rule measured_calibration:
    input:
        "results/figures/measured_calibration.png",
        "results/figures/measured_calibration.pdf",


rule measured_residuals:
    input:
        "results/figures/measured_residuals.png",
        "results/figures/measured_residuals.pdf",


rule measured:
    """The whole stage: tables, the peer, claims and the three figures."""
    input:
        expand("results/measured/{t}.csv", t=MEASURED_TABLES),
        MEASURED_PEER,
        "results/claims/measured.csv",
        expand("results/figures/{f}.{ext}", f=("measured_static_detection", "measured_calibration",
                                                 "measured_residuals"), ext=("png", "pdf")),
