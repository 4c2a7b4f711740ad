"""Stage 'discrepancy': where simulation and measured data disagree, which effect or noise
term is missing, and a benchmark under realistic noise that scores it.

* ADIS16405 (the 2.78 h static record): Allan deviation to ~1000 s, the library's noise
  terms fitted to it, and what calibration-length rests predict (``discrepancy_adis*``);
  ``discrepancy_adis_fetch`` locates or downloads the record first.
* Benchmark: ``discrepancy_profiles`` resolves the noise profiles (parametric, fitted to
  the Xsens rests and the ADIS record, and windows of the ADIS record); each
  ``discrepancy_chunk`` job simulates its recordings and runs the loop on each under
  every null hypothesis, in memory (the detection gets the recording only, never the
  key); ``discrepancy_score`` joins detections and key; ``discrepancy_timing`` records
  the benchmark's job-seconds.
* Measured: ``discrepancy_measured_report`` runs both layers (what ``accelcal
  discrepancy`` does) on the canonical CSV of a measured recording (rule measured_fetch writes it).
* results/discrepancy/summary.csv: the benchmark's findings and those on the real
  recordings; results/claims/discrepancy.csv: the claims.

Config: section ``discrepancy`` (its cross-key rules: _check_discrepancy, common.smk).
Needs from common.smk: declare_stage, stage_figures, results, log_path, bench_path, figure_files,
figure_outputs, MEASURED_CSV, MEASURED_SUMMARY, measured_data_dir, fitted_to_xsens, SMALL;
from measured.smk: rule measured_fetch (the canonical CSV) and the ``measured`` config (g of each
recording), read from the config only, so that the includes work in any order.
"""

DISCREPANCY = config["discrepancy"]


# The stage's config rules that its schema cannot express (one line naming the key).
def fitted_to_xsens(bench):
    """Whether a discrepancy benchmark profile is fitted to the Xsens session (its stochastic layer)."""
    return any(p.get("fitted") in ("xsens_mti", "xsens_mti_joint") for p in bench["profiles"])


def _check_discrepancy(d, cfg):
    bench, sessions = d["benchmark"], d["sessions"]
    if not any(abs(s - bench["confusion_size_mde"]) < 1e-12 for s in bench["sizes_mde"]):
        raise _config_error("discrepancy.benchmark.confusion_size_mde",
                            f"{bench['confusion_size_mde']} is not in sizes_mde {bench['sizes_mde']}")
    measured = cfg["measured"]["recordings"]
    missing = [r for r in d["recordings"] if r not in measured]
    if missing:
        raise _config_error("discrepancy.recordings", f"{', '.join(missing)} not in measured.recordings")
    profiles = [p["name"] for p in bench["profiles"]]
    if len(set(profiles)) != len(profiles):
        raise _config_error("discrepancy.benchmark.profiles", "profile names must be distinct")
    unknown = [p for p in bench["power_curve"]["profiles"] if p not in profiles]
    if unknown:
        raise _config_error("discrepancy.benchmark.power_curve.profiles", f"{', '.join(unknown)} not in profiles")
    few = [r for r in sessions["few_poses"] if r not in measured]
    if few:
        raise _config_error("discrepancy.sessions.few_poses", f"{', '.join(few)} not in measured.recordings")
    for group, members in sessions["same_imu"].items():
        missing = [m for m in members if m not in d["recordings"]]
        if missing:
            raise _config_error(f"discrepancy.sessions.same_imu.{group}",
                                f"{', '.join(missing)} not in discrepancy.recordings")
    if fitted_to_xsens(bench) and "xsens_mti" not in d["recordings"]:
        raise _config_error("discrepancy.benchmark.profiles",
                            "a profile is fitted to xsens_mti, which is not in discrepancy.recordings")


check_section("discrepancy", _check_discrepancy)
DISCREPANCY_SESSIONS = DISCREPANCY["sessions"]
DISCREPANCY_BENCH = DISCREPANCY["benchmark"]
DISCREPANCY_CHUNKS = list(range(DISCREPANCY_BENCH["chunks"]))
DISCREPANCY_RECORDINGS = list(DISCREPANCY["recordings"])
DISCREPANCY_PROFILES = [p["name"] for p in DISCREPANCY_BENCH["profiles"]]
#: Profiles that need the Xsens report (its stochastic layer's fit) or the ADIS record.
DISCREPANCY_NEEDS_XSENS = fitted_to_xsens(DISCREPANCY_BENCH)
DISCREPANCY_NEEDS_RECORD = any(p.get("real") for p in DISCREPANCY_BENCH["profiles"])
ADIS_DATASET, ADIS_FILE = "smac_adis16405", "adis_16405_imu1.rda"

# Outputs read by several rules, each path written once.
ADIS_DIR = results("discrepancy/adis")
ADIS_NOISE = f"{ADIS_DIR}/noise.npy"
ADIS_MODELS = f"{ADIS_DIR}/models.csv"
ADIS_CHECK_SUMMARY = f"{ADIS_DIR}/session_check_summary.csv"
BENCH_DIR = results("discrepancy/benchmark")
BENCH_PROFILES = f"{BENCH_DIR}/profiles.csv"
BENCH_SUMMARY = f"{BENCH_DIR}/summary.csv"
BENCH_RATES = f"{BENCH_DIR}/rates.csv"
BENCH_KEY = f"{BENCH_DIR}/key/chunk_{{chunk}}.csv"
BENCH_DETECTIONS = f"{BENCH_DIR}/detections/chunk_{{chunk}}.csv"
#: Both layers on one real recording (the JSON `accelcal discrepancy` writes).
RECORDING_REPORT = results("discrepancy/measured/{recording}.json")
SESSIONS_DIR = results("discrepancy/sessions")
SESSION_RESIM = f"{SESSIONS_DIR}/{{recording}}_resim.csv.gz"
SESSION_GAP = f"{SESSIONS_DIR}/{{recording}}_gap.csv"
SESSIONS_GAPS = f"{SESSIONS_DIR}/gaps.csv"
SESSIONS_EXCESS = f"{SESSIONS_DIR}/excess.csv"
SESSIONS_STABILITY = f"{SESSIONS_DIR}/stability.csv"
SESSIONS_ESTIMATES = f"{SESSIONS_DIR}/estimates.csv"
DISCREPANCY_SUMMARY = results("discrepancy/summary.csv")


def per_recording(pattern, recordings=DISCREPANCY_RECORDINGS):
    """``pattern`` for each of the stage's recordings."""
    return expand(pattern, recording=recordings)


DISCREPANCY_STAGE = declare_stage(
    name="discrepancy",
    figures=["discrepancy_fpr", "discrepancy_confusion", "discrepancy_power", "discrepancy_rows",
             "discrepancy_adis_allan", "discrepancy_measured_before_after", "discrepancy_allan", "discrepancy_sessions",
             "discrepancy_evidence"]
    + (["discrepancy_stability"] if DISCREPANCY_SESSIONS["same_imu"] else []),
    tables=(
        ("Real sessions: pose-residual excess observed and predicted by the joint model", SESSIONS_EXCESS),
        ("Real sessions re-simulated before and after what the loop names: gap to the measured residuals",
         SESSIONS_GAPS),
        ("Discrepancy benchmark per noise profile: false-positive rate (wander and white null, and the oracle), "
         "naming accuracy, outliers and pairs", f"{BENCH_DIR}/headline.csv"),
        ("Discrepancy benchmark: the loop against the oracle (the same tests with the true noise covariance), "
         "per profile and row", f"{BENCH_DIR}/oracle.csv"),
        ("ADIS16405: observed and predicted pose-mean wander on session-shaped pieces", ADIS_CHECK_SUMMARY),
        ("Discrepancy summary", DISCREPANCY_SUMMARY),
    ),
    summaries=tuple((f"{r}: both layers (accelcal discrepancy)", summaries_path(f"discrepancy_{r}"))
                    for r in DISCREPANCY_RECORDINGS),
)


#: The benchmark keys a chunk reads (not the profiles' own: they come in profiles.json;
#: not the figures' confusion_size_mde): a new figure size reruns no chunk.
BENCH_CHUNK_KEYS = ("session", "nulls", "oracle", "sizes_mde", "seeds", "seeds_none", "seeds_none_real",
                    "seeds_constant", "pairs", "outlier", "power_curve", "chunks")


def _bench_params():
    """Everything that defines the benchmark's recordings and their detection."""
    return dict(seed=DISCREPANCY["seed"], benchmark=config_keys(DISCREPANCY_BENCH, *BENCH_CHUNK_KEYS),
                rules=DISCREPANCY["rules"])


rule discrepancy_adis_fetch:
    """Locate (shared copy) or download and verify (sha256) the ADIS16405 record, as
    measured_fetch does for the recordings; the manifest records which path was used.
    High priority: a failing download stops the run before the long jobs."""
    priority: 100
    localrule: True  # on a cluster: the login node (internet access; a checksum when the data is local)
    output:
        f"{ADIS_DIR}/data.json",
    params:
        dataset=ADIS_DATASET,
        files=[ADIS_FILE],
        data_dir=measured_data_dir(),
        resources_dir=config["measured"]["resources_dir"],
    log:
        log_path("discrepancy/adis_fetch"),
    benchmark:
        bench_path("discrepancy/adis_fetch"),
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,  # a download of 3.2 MB
    script:
        "../scripts/discrepancy_adis_fetch.py"


rule discrepancy_adis:
    """The ADIS16405 record: Allan deviation, the library's models fitted on tau >= tau_min,
    and its noise (m/s², about its mean) for the benchmark's real-noise profile."""
    input:
        manifest=f"{ADIS_DIR}/data.json",
    output:
        allan=f"{ADIS_DIR}/allan.csv",
        models=ADIS_MODELS,
        curves=f"{ADIS_DIR}/curves.csv",
        noise=ADIS_NOISE,
    params:
        file=ADIS_FILE,
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
        noise=ADIS_NOISE,
        models=ADIS_MODELS,
    output:
        check=f"{ADIS_DIR}/session_check.csv",
        summary=ADIS_CHECK_SUMMARY,
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
        models=ADIS_MODELS,
        xsens=per_recording(RECORDING_REPORT, ["xsens_mti"]) if DISCREPANCY_NEEDS_XSENS else [],
        record=[ADIS_NOISE] if DISCREPANCY_NEEDS_RECORD else [],
        kernel_cache=KERNEL_CACHE,
    output:
        profiles=f"{BENCH_DIR}/profiles.json",
        table=BENCH_PROFILES,
        screen=f"{BENCH_DIR}/record_screen.csv",
    params:
        benchmark=config_keys(DISCREPANCY_BENCH, "session", "profiles", "record_screen"),
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
        profiles=f"{BENCH_DIR}/profiles.json",
        record=[ADIS_NOISE] if DISCREPANCY_NEEDS_RECORD else [],
        kernel_cache=KERNEL_CACHE,
    output:
        key=BENCH_KEY,
        detections=BENCH_DETECTIONS,
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
    """Join detections and key: one row per recording and null (the oracle a null of its own), rates, summary,
    headline, and where the loop and the oracle differ."""
    input:
        key=expand(BENCH_KEY, chunk=DISCREPANCY_CHUNKS),
        detections=expand(BENCH_DETECTIONS, chunk=DISCREPANCY_CHUNKS),
    output:
        scores=f"{BENCH_DIR}/scores.csv.gz",
        rates=BENCH_RATES,
        summary=BENCH_SUMMARY,
        headline=f"{BENCH_DIR}/headline.csv",
        oracle=f"{BENCH_DIR}/oracle.csv",
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
        # the stage's one figure job draws the benchmark's four figures and six others
        other=[bench_path(f"discrepancy/{j}") for j in ("adis", "profiles", "score", "figures")],
    output:
        f"{BENCH_DIR}/timing.csv",
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
        csv=MEASURED_CSV,
    output:
        RECORDING_REPORT,
        summaries=summaries_path("discrepancy_{recording}"),
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
        report=RECORDING_REPORT,
        csv=MEASURED_CSV,
        kernel_cache=KERNEL_CACHE,
    output:
        sims=SESSION_RESIM,
        gap=SESSION_GAP,
    params:
        sessions=config_keys(DISCREPANCY_SESSIONS, "replicates", "seed"),
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
        csv=MEASURED_CSV,
        measured_summary=MEASURED_SUMMARY,
        kernel_cache=KERNEL_CACHE,
    output:
        f"{SESSIONS_DIR}/{{recording}}_few_poses.json",
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
        reports=per_recording(RECORDING_REPORT),
        gaps=per_recording(SESSION_GAP),
        few_poses=per_recording(f"{SESSIONS_DIR}/{{recording}}_few_poses.json", DISCREPANCY_SESSIONS["few_poses"]),
        csv=per_recording(MEASURED_CSV),
    output:
        named=f"{SESSIONS_DIR}/named.csv",
        excess=SESSIONS_EXCESS,
        gaps=SESSIONS_GAPS,
        evidence=f"{SESSIONS_DIR}/evidence.csv",
        diagnostics=f"{SESSIONS_DIR}/diagnostics.csv",
        estimates=SESSIONS_ESTIMATES,
        stability=SESSIONS_STABILITY,
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
        benchmark=BENCH_SUMMARY,
        reports=per_recording(RECORDING_REPORT),
        measured_summary=MEASURED_SUMMARY,
    output:
        summary=DISCREPANCY_SUMMARY,
        candidates=results("discrepancy/measured.csv"),
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
    """results/claims/discrepancy.csv: the stage's goals judged on the benchmark, the ADIS check
    and the real sessions."""
    input:
        summary=BENCH_SUMMARY,
        profiles=BENCH_PROFILES,
        adis=ADIS_CHECK_SUMMARY,
        stability=SESSIONS_STABILITY,
        excess=SESSIONS_EXCESS,
        gaps=SESSIONS_GAPS,
    output:
        results("claims/discrepancy.csv"),
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
# One job draws every figure of the stage (common.smk's stage_figures).  Inputs per figure:
DISCREPANCY_FIGURE_INPUTS = {
    "discrepancy_fpr": {"summary": BENCH_SUMMARY, "profiles": BENCH_PROFILES},
    "discrepancy_confusion": {"scores": f"{BENCH_DIR}/scores.csv.gz"},
    "discrepancy_power": {"rates": BENCH_RATES},
    "discrepancy_rows": {"rates": BENCH_RATES},
    "discrepancy_adis_allan": {"curves": f"{ADIS_DIR}/curves.csv", "allan": f"{ADIS_DIR}/allan.csv",
                               "check": ADIS_CHECK_SUMMARY},
    "discrepancy_measured_before_after": {"reports": per_recording(RECORDING_REPORT)},
    "discrepancy_allan": {"reports": per_recording(RECORDING_REPORT)},
    "discrepancy_sessions": {"reports": per_recording(RECORDING_REPORT), "sims": per_recording(SESSION_RESIM),
                             "gaps": SESSIONS_GAPS},
    "discrepancy_stability": {"stability": SESSIONS_STABILITY, "estimates": SESSIONS_ESTIMATES},
    "discrepancy_evidence": {"reports": per_recording(RECORDING_REPORT), "evidence": f"{SESSIONS_DIR}/evidence.csv"},
}


stage_figures(
    DISCREPANCY_STAGE,
    DISCREPANCY_FIGURE_INPUTS,
    "Discrepancy",
    "../scripts/discrepancy_figure.py",
    params=dict(
        rules=DISCREPANCY["rules"],
        confusion_size=DISCREPANCY_BENCH["confusion_size_mde"],
        profiles=DISCREPANCY_PROFILES,
        curve_profiles=DISCREPANCY_BENCH["power_curve"]["profiles"],
        sizes=DISCREPANCY_BENCH["sizes_mde"],
        recordings=DISCREPANCY_RECORDINGS,
    ),
)


rule discrepancy_benchmark:
    """The benchmark: scores, rates, summary, timing and its figures."""
    input:
        BENCH_SUMMARY,
        f"{BENCH_DIR}/headline.csv",
        f"{BENCH_DIR}/oracle.csv",
        f"{BENCH_DIR}/timing.csv",
        figure_files("discrepancy_fpr", "discrepancy_confusion", "discrepancy_power", "discrepancy_rows"),


rule discrepancy_adis_reference:
    """The ADIS16405 reference: tables and figure."""
    input:
        ADIS_CHECK_SUMMARY,
        figure_files("discrepancy_adis_allan"),


rule discrepancy_measured:
    """The real recordings: both layers' reports, the session study and its figures."""
    input:
        per_recording(RECORDING_REPORT),
        SESSIONS_STABILITY,
        figure_files(*[f for f in DISCREPANCY_STAGE.figures if f in ("discrepancy_measured_before_after",
                                                                      "discrepancy_allan", "discrepancy_sessions",
                                                                      "discrepancy_evidence", "discrepancy_stability")]),


rule discrepancy:
    """The whole stage: benchmark, ADIS reference, measured recordings, summary, claims, figures."""
    input:
        rules.discrepancy_benchmark.input,
        rules.discrepancy_adis_reference.input,
        rules.discrepancy_measured.input,
        DISCREPANCY_SUMMARY,
        results("discrepancy/measured.csv"),
        results("claims/discrepancy.csv"),
