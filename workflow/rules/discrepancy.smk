"""Stage 'discrepancy' (issues 7 and 13): where simulation and measured data disagree, which
effect or noise term is missing, and a benchmark under realistic noise that scores it.

* ADIS16405 (the 2.78 h static record): Allan deviation to ~1000 s, the library's noise
  terms fitted to it, and what calibration-length rests predict (``discrepancy_adis*``).
* Benchmark: ``discrepancy_profiles`` resolves the noise profiles (parametric, fitted to
  the Xsens rests and the ADIS record, and windows of the ADIS record); each
  ``discrepancy_chunk`` job simulates its recordings and runs the loop on each under
  every null hypothesis, in memory (the detection gets the recording only, never the
  key); ``discrepancy_score`` joins detections and key; ``discrepancy_timing`` records
  the benchmark's job-seconds.
* Measured: ``discrepancy_measured_report`` runs both layers (what ``accelcal
  discrepancy`` does) on the canonical CSV of a measured recording (rule measured_convert).
* results/discrepancy/summary.csv: the benchmark's findings and those on the real
  recordings; results/claims/discrepancy.csv: the claims.

Config: section ``discrepancy``.  Needs from common.smk: FIGURES, CLAIM_STAGES,
REPORT_TABLES, log_path, bench_path, figure_outputs, SMALL, _config_error; from
measured.smk: rule measured_convert and the ``measured`` config (g of each recording,
data folders), read from the config only, so that the includes work in any order.
"""

import os

from snakemake.exceptions import WorkflowError

from accelcal_repro.measured.data import DatasetError, check_available

DISCREPANCY = config["discrepancy"]
DISCREPANCY_SESSIONS = DISCREPANCY["sessions"]
DISCREPANCY_FIGURES = ["discrepancy_fpr", "discrepancy_confusion", "discrepancy_power", "discrepancy_rows",
                       "discrepancy_adis_allan", "discrepancy_measured_before_after", "discrepancy_allan",
                       "discrepancy_sessions"] + (["discrepancy_stability"] if DISCREPANCY_SESSIONS["same_imu"] else [])
FIGURES.extend(DISCREPANCY_FIGURES)
CLAIM_STAGES.append("discrepancy")
REPORT_TABLES.extend([
    ("discrepancy", "Real sessions: pose-residual excess observed and predicted by the joint model",
     "results/discrepancy/sessions/excess.csv"),
    ("discrepancy", "Real sessions re-simulated before and after what the loop names: gap to the measured residuals",
     "results/discrepancy/sessions/gaps.csv"),
    ("discrepancy", "Discrepancy benchmark per noise profile: false-positive rate (colored and white null), "
     "naming accuracy, outliers and pairs", "results/discrepancy/benchmark/headline.csv"),
    ("discrepancy", "ADIS16405: observed and predicted pose-mean wander on session-shaped pieces",
     "results/discrepancy/adis/session_check_summary.csv"),
])
DISCREPANCY_BENCH = DISCREPANCY["benchmark"]
DISCREPANCY_CHUNKS = list(range(DISCREPANCY_BENCH["chunks"]))
DISCREPANCY_RECORDINGS = list(DISCREPANCY["recordings"])
DISCREPANCY_PROFILES = [p["name"] for p in DISCREPANCY_BENCH["profiles"]]
#: Profiles that need the Xsens report (its stochastic layer's fit) or the ADIS record.
DISCREPANCY_NEEDS_XSENS = any(p.get("fitted") in ("xsens_mti", "xsens_mti_joint") for p in DISCREPANCY_BENCH["profiles"])
DISCREPANCY_NEEDS_RECORD = any(p.get("real") for p in DISCREPANCY_BENCH["profiles"])
ADIS_DATASET, ADIS_FILE = "smac_adis16405", "adis_16405_imu1.rda"
#: As measured.smk: a relative data_dir is taken from the project root.
DISCREPANCY_DATA_DIR = os.path.normpath(os.path.join(workflow.basedir, config["measured"]["data_dir"]))


class DiscrepancyDataError(WorkflowError):
    """The ADIS record is neither local nor downloadable (one line)."""


def _discrepancy_check():
    # Cross-key rules a JSON schema cannot express; one line naming the key.
    bench = DISCREPANCY_BENCH
    if not any(abs(s - bench["confusion_size_mde"]) < 1e-12 for s in bench["sizes_mde"]):
        raise _config_error("discrepancy.benchmark.confusion_size_mde",
                            f"{bench['confusion_size_mde']} is not in sizes_mde {bench['sizes_mde']}")
    missing = [r for r in DISCREPANCY_RECORDINGS if r not in config["measured"]["recordings"]]
    if missing:
        raise _config_error("discrepancy.recordings", f"{', '.join(missing)} not in measured.recordings")
    if len(set(DISCREPANCY_PROFILES)) != len(DISCREPANCY_PROFILES):
        raise _config_error("discrepancy.benchmark.profiles", "profile names must be distinct")
    unknown = [p for p in bench["power_curve"]["profiles"] if p not in DISCREPANCY_PROFILES]
    if unknown:
        raise _config_error("discrepancy.benchmark.power_curve.profiles", f"{', '.join(unknown)} not in profiles")
    few = [r for r in DISCREPANCY_SESSIONS["few_poses"] if r not in config["measured"]["recordings"]]
    if few:
        raise _config_error("discrepancy.sessions.few_poses", f"{', '.join(few)} not in measured.recordings")
    for group, members in DISCREPANCY_SESSIONS["same_imu"].items():
        missing = [m for m in members if m not in DISCREPANCY_RECORDINGS]
        if missing:
            raise _config_error(f"discrepancy.sessions.same_imu.{group}",
                                f"{', '.join(missing)} not in discrepancy.recordings")
    if DISCREPANCY_NEEDS_XSENS and "xsens_mti" not in DISCREPANCY_RECORDINGS:
        raise _config_error("discrepancy.benchmark.profiles",
                            "a profile is fitted to xsens_mti, which is not in discrepancy.recordings")
    try:
        check_available(ADIS_DATASET, ADIS_FILE, DISCREPANCY_DATA_DIR, config["measured"]["resources_dir"])
    except DatasetError as e:
        raise DiscrepancyDataError(f"missing measured data: {e}") from None


_discrepancy_check()


def _bench_params():
    """Everything that defines the benchmark's recordings and their detection."""
    return dict(seed=DISCREPANCY["seed"], benchmark=DISCREPANCY_BENCH, rules=DISCREPANCY["rules"])


rule discrepancy_adis:
    """The ADIS16405 record: Allan deviation, the library's models fitted on tau >= tau_min,
    and its noise (m/s², about its mean) for the benchmark's real-noise profile."""
    output:
        allan="results/discrepancy/adis/allan.csv",
        models="results/discrepancy/adis/models.csv",
        curves="results/discrepancy/adis/curves.csv",
        noise="results/discrepancy/adis/noise.npy",
    params:
        dataset=ADIS_DATASET,
        file=ADIS_FILE,
        data_dir=DISCREPANCY_DATA_DIR,
        resources_dir=config["measured"]["resources_dir"],
        adis=DISCREPANCY["adis"],
    log:
        log_path("discrepancy/adis"),
    benchmark:
        bench_path("discrepancy/adis"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,  # reading the R file ~3 s, 32 model fits per axis ~3 s
    script:
        "../scripts/discrepancy_adis.py"


rule discrepancy_adis_sessions:
    """Session-shaped pieces of the ADIS record: observed pose-mean wander vs the reference
    model and vs the stochastic layer run on the pieces' own rests."""
    input:
        noise="results/discrepancy/adis/noise.npy",
        models="results/discrepancy/adis/models.csv",
    output:
        check="results/discrepancy/adis/session_check.csv",
        summary="results/discrepancy/adis/session_check_summary.csv",
    params:
        adis=DISCREPANCY["adis"],
        session=DISCREPANCY_BENCH["session"],
        candidates=DISCREPANCY["stochastic"]["candidates"],
    log:
        log_path("discrepancy/adis_sessions"),
    benchmark:
        bench_path("discrepancy/adis_sessions"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=15,  # default config: the stochastic layer on 6 pieces, ~6 s each
    script:
        "../scripts/discrepancy_adis_sessions.py"


rule discrepancy_profiles:
    """The benchmark's noise profiles resolved to counts (profiles.json), what each does to
    the pose means of the session (profiles.csv), and the transients the pre-registered
    screen finds in the real record (record_screen.csv: the windows it leaves out)."""
    localrule: True  # on a cluster: the login node (a gather between two groups of SLURM jobs)
    input:
        models="results/discrepancy/adis/models.csv",
        xsens=["results/discrepancy/measured/xsens_mti.json"] if DISCREPANCY_NEEDS_XSENS else [],
        record=["results/discrepancy/adis/noise.npy"] if DISCREPANCY_NEEDS_RECORD else [],
    output:
        profiles="results/discrepancy/benchmark/profiles.json",
        table="results/discrepancy/benchmark/profiles.csv",
        screen="results/discrepancy/benchmark/record_screen.csv",
    params:
        benchmark=DISCREPANCY_BENCH,
    log:
        log_path("discrepancy/profiles"),
    benchmark:
        bench_path("discrepancy/profiles"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_profiles.py"


rule discrepancy_chunk:
    """One chunk of the benchmark: simulate each recording (the key row apart) and run the
    loop on it under every null hypothesis."""
    input:
        profiles="results/discrepancy/benchmark/profiles.json",
        record=["results/discrepancy/adis/noise.npy"] if DISCREPANCY_NEEDS_RECORD else [],
    output:
        key="results/discrepancy/benchmark/key/chunk_{chunk}.csv",
        detections="results/discrepancy/benchmark/detections/chunk_{chunk}.csv",
    params:
        chunk=lambda w: int(w.chunk),
        **_bench_params(),
    wildcard_constraints:
        chunk=r"\d+",
    log:
        log_path("discrepancy/chunk_{chunk}"),
    benchmark:
        bench_path("discrepancy/chunk_{chunk}"),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    script:
        "../scripts/discrepancy_chunk.py"


rule discrepancy_score:
    """Join detections and key: one row per recording and null, rates, summary, headline."""
    input:
        key=expand("results/discrepancy/benchmark/key/chunk_{chunk}.csv", chunk=DISCREPANCY_CHUNKS),
        detections=expand("results/discrepancy/benchmark/detections/chunk_{chunk}.csv", chunk=DISCREPANCY_CHUNKS),
    output:
        scores="results/discrepancy/benchmark/scores.csv.gz",
        rates="results/discrepancy/benchmark/rates.csv",
        summary="results/discrepancy/benchmark/summary.csv",
        headline="results/discrepancy/benchmark/headline.csv",
    params:
        rules=DISCREPANCY["rules"],
        confusion_size=DISCREPANCY_BENCH["confusion_size_mde"],
        profiles=DISCREPANCY_PROFILES,
    log:
        log_path("discrepancy/score"),
    benchmark:
        bench_path("discrepancy/score"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_score.py"


rule discrepancy_timing:
    """Job-seconds of the benchmark (wall and CPU of every job that makes it), from the jobs'
    benchmark files: not byte-identical on a rerun (hence 'timing' in the name)."""
    input:
        chunks=expand(bench_path("discrepancy/chunk_{chunk}"), chunk=DISCREPANCY_CHUNKS),
        other=[bench_path(f"discrepancy/{j}") for j in ("adis", "profiles", "score", "discrepancy_fpr_figure",
                                                        "discrepancy_confusion_figure", "discrepancy_power_figure",
                                                        "discrepancy_rows_figure")],
    output:
        "results/discrepancy/benchmark/timing.csv",
    params:
        chunks=DISCREPANCY_BENCH["chunks"],
    log:
        log_path("discrepancy/timing"),
    benchmark:
        bench_path("discrepancy/timing"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_timing.py"


rule discrepancy_measured_report:
    """Both layers on one measured recording: the report `accelcal discrepancy` writes."""
    input:
        csv="results/measured/{recording}.csv",
    output:
        "results/discrepancy/measured/{recording}.json",
    params:
        g=lambda w: config["measured"]["recordings"][w.recording]["g"],
        rules=DISCREPANCY["rules"],
        stochastic=DISCREPANCY["stochastic"],
    log:
        log_path("discrepancy/measured_{recording}"),
    benchmark:
        bench_path("discrepancy/measured_{recording}"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,  # the stochastic layer's bootstrap dominates
    script:
        "../scripts/discrepancy_measured.py"


rule discrepancy_session:
    """One real session re-simulated under the model before and after what the loop named,
    through the same pose extraction and base fit as the measured data."""
    input:
        report="results/discrepancy/measured/{recording}.json",
        csv="results/measured/{recording}.csv",
    output:
        sims="results/discrepancy/sessions/{recording}_resim.csv.gz",
        gap="results/discrepancy/sessions/{recording}_gap.csv",
    params:
        sessions=DISCREPANCY_SESSIONS,
    log:
        log_path("discrepancy/session_{recording}"),
    benchmark:
        bench_path("discrepancy/session_{recording}"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=15,  # default config: 200 re-simulations of about 0.05 s
    script:
        "../scripts/discrepancy_session.py"


rule discrepancy_few_poses:
    """A session of too few orientations for the loop: what can be tested, and what cannot and why."""
    input:
        csv="results/measured/{recording}.csv",
        measured_summary="results/measured/summary.csv",
    output:
        "results/discrepancy/sessions/{recording}_few_poses.json",
    params:
        stochastic=DISCREPANCY["stochastic"],
    log:
        log_path("discrepancy/few_poses_{recording}"),
    benchmark:
        bench_path("discrepancy/few_poses_{recording}"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_few_poses.py"


rule discrepancy_sessions_tables:
    """Every real session: what is named, excess observed vs predicted, the re-simulation gaps,
    the evidence per candidate, and the session-to-session stability of one IMU."""
    input:
        reports=expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
        gaps=expand("results/discrepancy/sessions/{recording}_gap.csv", recording=DISCREPANCY_RECORDINGS),
        few_poses=expand("results/discrepancy/sessions/{recording}_few_poses.json",
                         recording=DISCREPANCY_SESSIONS["few_poses"]),
        csv=expand("results/measured/{recording}.csv", recording=DISCREPANCY_RECORDINGS),
    output:
        named="results/discrepancy/sessions/named.csv",
        excess="results/discrepancy/sessions/excess.csv",
        gaps="results/discrepancy/sessions/gaps.csv",
        evidence="results/discrepancy/sessions/evidence.csv",
        diagnostics="results/discrepancy/sessions/diagnostics.csv",
        estimates="results/discrepancy/sessions/estimates.csv",
        stability="results/discrepancy/sessions/stability.csv",
    params:
        recordings=DISCREPANCY_RECORDINGS,
        same_imu=DISCREPANCY_SESSIONS["same_imu"],
        alpha=DISCREPANCY["rules"]["alpha"],
    log:
        log_path("discrepancy/sessions"),
    benchmark:
        bench_path("discrepancy/sessions"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_sessions.py"


rule discrepancy_summary:
    """results/discrepancy/summary.csv (benchmark scores + measured findings) and the
    tidy table of every measured candidate test (results/discrepancy/measured.csv)."""
    input:
        benchmark="results/discrepancy/benchmark/summary.csv",
        reports=expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
        measured_summary="results/measured/summary.csv",
    output:
        summary="results/discrepancy/summary.csv",
        candidates="results/discrepancy/measured.csv",
    params:
        recordings=DISCREPANCY_RECORDINGS,
    log:
        log_path("discrepancy/summary"),
    benchmark:
        bench_path("discrepancy/summary"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_summary.py"


rule discrepancy_claims:
    """results/claims/discrepancy.csv: the issue's goals judged on the benchmark and the ADIS check."""
    input:
        summary="results/discrepancy/benchmark/summary.csv",
        profiles="results/discrepancy/benchmark/profiles.csv",
        adis="results/discrepancy/adis/session_check_summary.csv",
        stability="results/discrepancy/sessions/stability.csv",
        excess="results/discrepancy/sessions/excess.csv",
        gaps="results/discrepancy/sessions/gaps.csv",
    output:
        "results/claims/discrepancy.csv",
    params:
        rules=DISCREPANCY["rules"],
        nulls=DISCREPANCY_BENCH["nulls"],
    log:
        log_path("discrepancy/claims"),
    benchmark:
        bench_path("discrepancy/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_claims.py"


# --------------------------------------------------------------------------- figures
# One script draws every figure of the stage; the figure id is a param.  Inputs per figure:
DISCREPANCY_FIGURE_INPUTS = {
    "discrepancy_fpr": {"summary": "results/discrepancy/benchmark/summary.csv",
                        "profiles": "results/discrepancy/benchmark/profiles.csv"},
    "discrepancy_confusion": {"scores": "results/discrepancy/benchmark/scores.csv.gz"},
    "discrepancy_power": {"rates": "results/discrepancy/benchmark/rates.csv"},
    "discrepancy_rows": {"rates": "results/discrepancy/benchmark/rates.csv"},
    "discrepancy_adis_allan": {"curves": "results/discrepancy/adis/curves.csv",
                               "allan": "results/discrepancy/adis/allan.csv",
                               "check": "results/discrepancy/adis/session_check_summary.csv"},
    "discrepancy_measured_before_after": {
        "reports": expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS)},
    "discrepancy_allan": {
        "reports": expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS)},
    "discrepancy_sessions": {
        "reports": expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
        "sims": expand("results/discrepancy/sessions/{recording}_resim.csv.gz", recording=DISCREPANCY_RECORDINGS),
        "gaps": "results/discrepancy/sessions/gaps.csv"},
    "discrepancy_stability": {"stability": "results/discrepancy/sessions/stability.csv",
                              "estimates": "results/discrepancy/sessions/estimates.csv"},
}


for _fid in DISCREPANCY_FIGURES:

    rule:
        name:
            f"{_fid}_figure"
        input:
            **DISCREPANCY_FIGURE_INPUTS[_fid],
        output:
            **figure_outputs(_fid, f"../report/{_fid}.rst", "Discrepancy"),
        params:
            figure=_fid,
            rules=DISCREPANCY["rules"],
            confusion_size=DISCREPANCY_BENCH["confusion_size_mde"],
            profiles=DISCREPANCY_PROFILES,
            curve_profiles=DISCREPANCY_BENCH["power_curve"]["profiles"],
            sizes=DISCREPANCY_BENCH["sizes_mde"],
            recordings=DISCREPANCY_RECORDINGS,
        log:
            log_path(f"discrepancy/{_fid}_figure"),
        benchmark:
            bench_path(f"discrepancy/{_fid}_figure"),
        threads: 1
        resources:
            **SMALL,
        script:
            "../scripts/discrepancy_figure.py"

    # The figure id as a target: `snakemake discrepancy_fpr`.
    rule:
        name:
            _fid
        input:
            f"results/figures/{_fid}.png",
            f"results/figures/{_fid}.pdf",


rule discrepancy_benchmark:
    """The benchmark: scores, rates, summary, timing and its figures."""
    input:
        "results/discrepancy/benchmark/summary.csv",
        "results/discrepancy/benchmark/headline.csv",
        "results/discrepancy/benchmark/timing.csv",
        expand("results/figures/{f}.{ext}", ext=("png", "pdf"),
               f=("discrepancy_fpr", "discrepancy_confusion", "discrepancy_power", "discrepancy_rows")),


rule discrepancy_adis_reference:
    """The ADIS16405 reference: tables and figure."""
    input:
        "results/discrepancy/adis/session_check_summary.csv",
        expand("results/figures/discrepancy_adis_allan.{ext}", ext=("png", "pdf")),


rule discrepancy_measured:
    """The real recordings: both layers' reports, the session study and its figures."""
    input:
        expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
        "results/discrepancy/sessions/stability.csv",
        expand("results/figures/{f}.{ext}", ext=("png", "pdf"),
               f=[f for f in DISCREPANCY_FIGURES if f in ("discrepancy_measured_before_after", "discrepancy_allan",
                                                          "discrepancy_sessions", "discrepancy_stability")]),


rule discrepancy:
    """The whole stage: benchmark, ADIS reference, measured recordings, summary, claims, figures."""
    input:
        rules.discrepancy_benchmark.input,
        rules.discrepancy_adis_reference.input,
        rules.discrepancy_measured.input,
        "results/discrepancy/summary.csv",
        "results/discrepancy/measured.csv",
        "results/claims/discrepancy.csv",
