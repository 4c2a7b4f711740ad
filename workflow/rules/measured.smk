"""Stage 'measured': public real-IMU recordings, calibrated with every estimator their pose
count allows and evaluated without ground truth (noise-predicted χ², leave-one-pose-out,
bootstrap over poses, agreement, nominal sensitivities, and imucal's Ferraris calibration as
a peer).  Config: the `measured` mapping (section `measured` of config/config.yaml).

The data are fetched by a job (measured_fetch: the shared copy, else a verified download),
run first; stages that do not need them plan and run without them.

Needs from common.smk: declare_stage, stage_figures, results, log_path, bench_path, figure_files, figure_outputs,
MEASURED_CSV, MEASURED_SUMMARY, measured_data_dir, SMALL.
"""

import re

MEASURED = config["measured"]


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_measured(m, cfg):
    for name, rec in m["recordings"].items():
        _check_estimators(rec["estimators"], f"measured.recordings.{name}.estimators")
    # The six static positions of a section list allow bias-only estimators: checked by the
    # measured_calibrate job (accelcal_repro.measured.calibrate.check_section_list_estimators),
    # so that parsing imports no reproduction.


check_section("measured", _check_measured)
MEASURED_RECORDINGS = list(MEASURED["recordings"])
MEASURED_TABLES = ("poses", "params", "pose_errors", "summary", "agreement", "nominal")
#: The manifest of one recording's files (measured_fetch), read by every job on the recording.
MEASURED_MANIFEST = results("measured/data/{recording}.json")
#: The peer runs on the imucal session only if that recording is configured.
MEASURED_PEER_TABLE = results("measured/peer_imucal.csv")
MEASURED_PEER = [MEASURED_PEER_TABLE] if "imucal_ferraris" in MEASURED_RECORDINGS else []
MEASURED_STAGE = declare_stage(
    name="measured",
    figures=("measured_static_detection", "measured_calibration", "measured_residuals"),
    tables=(("Fit quality per recording and estimator (χ², leave-one-pose-out, bootstrap)", MEASURED_SUMMARY),
            ("Sensitivities against the data sheet", results("measured/nominal.csv")))
    + tuple(("imucal's Ferraris calibration against accelcal", p) for p in MEASURED_PEER),
    summaries=tuple((f"{r}: each estimator's calibration", summaries_path(f"measured_{r}")) for r in MEASURED_RECORDINGS),
)


wildcard_constraints:
    recording="|".join(re.escape(r) for r in MEASURED_RECORDINGS),


rule measured_fetch:
    """Locate (shared copy) or download and verify (sha256) every file of one recording;
    the manifest records which path was used.  No data file enters the repository.  The
    same job writes the recording as the canonical CSV of the CLI (t,ax,ay,az; file units),
    which the discrepancy stage and the figures read: a job of its own spent most of its
    CPU starting (0.3 s to read and write against ~1 s of Python and Snakemake per job).
    High priority: when a download is needed it runs first, before the long Monte Carlo
    jobs, so that a failing download stops the run early."""
    priority: 100
    localrule: True  # on a cluster: the login node (internet access; a checksum and one read when the data is local)
    output:
        manifest=MEASURED_MANIFEST,
        csv=MEASURED_CSV,
    params:
        data_dir=measured_data_dir(),
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


rule measured_calibrate:
    """Static detection, every configured estimator, χ², leave-one-pose-out, bootstrap; on
    the original file, read with the readers of `accelcal calibrate`."""
    input:
        manifest=MEASURED_MANIFEST,
        kernel_cache=KERNEL_CACHE,
    output:
        **{t: results(f"measured/{{recording}}/{t}.csv") for t in MEASURED_TABLES},
        summaries=summaries_path("measured_{recording}"),
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
        manifest=MEASURED_MANIFEST.format(recording="imucal_ferraris"),
        poses=results("measured/imucal_ferraris/poses.csv"),
    output:
        MEASURED_PEER_TABLE,
    params:
        grav=lambda w: MEASURED["recordings"]["imucal_ferraris"]["g"],
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
        **{t: expand(results("measured/{recording}/{t}.csv"), recording=MEASURED_RECORDINGS, t=[t])
           for t in MEASURED_TABLES},
    output:
        **{t: results(f"measured/{t}.csv") for t in MEASURED_TABLES},
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
        summary=MEASURED_SUMMARY,
        params=results("measured/params.csv"),
        nominal=results("measured/nominal.csv"),
        peer=MEASURED_PEER,
    output:
        results("claims/measured.csv"),
    log:
        log_path("measured/claims"),
    benchmark:
        bench_path("measured/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/measured_claims.py"


# One job draws every figure (rule measured_figures, common.smk's stage_figures).
stage_figures(
    MEASURED_STAGE,
    {
        "measured_static_detection": {"csv": expand(MEASURED_CSV, recording=MEASURED_RECORDINGS),
                                      "poses": results("measured/poses.csv")},
        "measured_calibration": {"params": results("measured/params.csv"), "peer": MEASURED_PEER},
        "measured_residuals": {"pose_errors": results("measured/pose_errors.csv")},
    },
    "Measured data",
    "../scripts/measured_figure.py",
    params=dict(recordings=MEASURED_RECORDINGS),
)


rule measured:
    """The whole stage: tables, the peer, claims and the three figures."""
    input:
        expand(results("measured/{t}.csv"), t=MEASURED_TABLES),
        MEASURED_PEER,
        results("claims/measured.csv"),
        figure_files(*MEASURED_STAGE.figures),
