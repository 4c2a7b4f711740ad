"""Stage 'discrepancy' (issue 7): where simulation and measured data disagree, which effect
or noise term is missing, and a benchmark with hidden effects that scores the detection.

* Benchmark: ``discrepancy_generate`` writes simulated raw recordings (canonical CSV,
  temporary) and a separate key, one chunk per job; ``discrepancy_detect`` reads only the
  recordings; ``discrepancy_score`` joins detections and key.
* Measured: ``discrepancy_measured_report`` runs both layers (what ``accelcal
  discrepancy`` does) on the canonical CSV of a measured recording (rule measured_convert).
* results/discrepancy/summary.csv: accuracy per effect, false-positive rate, sizes at 50 %
  and 95 % detection, and the findings on the real recordings.

Config: section ``discrepancy``.  Needs from common.smk: FIGURES, REPORT_TABLES,
log_path, bench_path, figure_outputs, SMALL; from measured.smk: rule measured_convert
and the ``measured`` config (g of each recording).
"""

DISCREPANCY = config["discrepancy"]
DISCREPANCY_FIGURES = ["discrepancy_confusion", "discrepancy_power", "discrepancy_measured_before_after",
                       "discrepancy_allan"]
FIGURES.extend(DISCREPANCY_FIGURES)
REPORT_TABLES.extend([
    ("discrepancy", "Discrepancy: benchmark scores and findings on the measured recordings",
     "results/discrepancy/summary.csv"),
])
DISCREPANCY_CHUNKS = list(range(DISCREPANCY["benchmark"]["chunks"]))
DISCREPANCY_RECORDINGS = list(DISCREPANCY["recordings"])


def _discrepancy_check():
    # Cross-key rules a JSON schema cannot express; one line naming the key.
    bench = DISCREPANCY["benchmark"]
    if not any(abs(s - bench["confusion_size_mde"]) < 1e-12 for s in bench["sizes_mde"]):
        raise _config_error("discrepancy.benchmark.confusion_size_mde",
                            f"{bench['confusion_size_mde']} is not in sizes_mde {bench['sizes_mde']}")
    missing = [r for r in DISCREPANCY_RECORDINGS if r not in config["measured"]["recordings"]]
    if missing:
        raise _config_error("discrepancy.recordings", f"{', '.join(missing)} not in measured.recordings")


_discrepancy_check()


rule discrepancy_generate:
    """Simulated recordings of one chunk (temporary) and their key (what was hidden)."""
    output:
        recordings=temp(directory("results/discrepancy/benchmark/recordings/chunk_{chunk}")),
        key="results/discrepancy/benchmark/key/chunk_{chunk}.csv",
    params:
        chunk=lambda w: int(w.chunk),
        chunks=DISCREPANCY["benchmark"]["chunks"],
        seed=DISCREPANCY["seed"],
        benchmark=DISCREPANCY["benchmark"],
        rules=DISCREPANCY["rules"],
    wildcard_constraints:
        chunk=r"\d+",
    log:
        log_path("discrepancy/generate_{chunk}"),
    benchmark:
        bench_path("discrepancy/generate_{chunk}"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=20,  # default config: 225 recordings of about 0.6 MB, ~0.1 s each
    script:
        "../scripts/discrepancy_generate.py"


rule discrepancy_detect:
    """The discrepancy loop on every recording of a chunk; reads the recordings, never the key."""
    input:
        recordings="results/discrepancy/benchmark/recordings/chunk_{chunk}",
    output:
        "results/discrepancy/benchmark/detections/chunk_{chunk}.csv",
    params:
        g=DISCREPANCY["benchmark"]["session"]["g"],
        rules=DISCREPANCY["rules"],
    wildcard_constraints:
        chunk=r"\d+",
    log:
        log_path("discrepancy/detect_{chunk}"),
    benchmark:
        bench_path("discrepancy/detect_{chunk}"),
    # Run a chunk's detection as soon as its recordings exist, so that few temporary
    # recording folders are on disk at a time.
    priority: 10
    threads: 1
    resources:
        mem_mb=1000,
        runtime=30,  # default config: 225 recordings, ~0.2 s each
    script:
        "../scripts/discrepancy_detect.py"


rule discrepancy_score:
    """Join detections and key: one row per recording, rates per effect and size, summary."""
    input:
        key=expand("results/discrepancy/benchmark/key/chunk_{chunk}.csv", chunk=DISCREPANCY_CHUNKS),
        detections=expand("results/discrepancy/benchmark/detections/chunk_{chunk}.csv", chunk=DISCREPANCY_CHUNKS),
    output:
        scores="results/discrepancy/benchmark/scores.csv",
        rates="results/discrepancy/benchmark/rates.csv",
        summary="results/discrepancy/benchmark/summary.csv",
    params:
        rules=DISCREPANCY["rules"],
        confusion_size=DISCREPANCY["benchmark"]["confusion_size_mde"],
    log:
        log_path("discrepancy/score"),
    benchmark:
        bench_path("discrepancy/score"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_score.py"


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


rule discrepancy_confusion_figure:
    input:
        scores="results/discrepancy/benchmark/scores.csv",
    output:
        **figure_outputs("discrepancy_confusion", "../report/discrepancy_confusion.rst", "Discrepancy"),
    params:
        figure="discrepancy_confusion",
        rules=DISCREPANCY["rules"],
        confusion_size=DISCREPANCY["benchmark"]["confusion_size_mde"],
    log:
        log_path("discrepancy/confusion_figure"),
    benchmark:
        bench_path("discrepancy/confusion_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_figure.py"


rule discrepancy_power_figure:
    input:
        rates="results/discrepancy/benchmark/rates.csv",
        summary="results/discrepancy/benchmark/summary.csv",
    output:
        **figure_outputs("discrepancy_power", "../report/discrepancy_power.rst", "Discrepancy"),
    params:
        figure="discrepancy_power",
        rules=DISCREPANCY["rules"],
    log:
        log_path("discrepancy/power_figure"),
    benchmark:
        bench_path("discrepancy/power_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_figure.py"


rule discrepancy_measured_before_after_figure:
    input:
        reports=expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
    output:
        **figure_outputs("discrepancy_measured_before_after", "../report/discrepancy_measured_before_after.rst",
                         "Discrepancy"),
    params:
        figure="discrepancy_measured_before_after",
        recordings=DISCREPANCY_RECORDINGS,
    log:
        log_path("discrepancy/measured_before_after_figure"),
    benchmark:
        bench_path("discrepancy/measured_before_after_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_figure.py"


rule discrepancy_allan_figure:
    input:
        reports=expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
    output:
        **figure_outputs("discrepancy_allan", "../report/discrepancy_allan.rst", "Discrepancy"),
    params:
        figure="discrepancy_allan",
        recordings=DISCREPANCY_RECORDINGS,
    log:
        log_path("discrepancy/allan_figure"),
    benchmark:
        bench_path("discrepancy/allan_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/discrepancy_figure.py"


# Figure ids as targets: `snakemake discrepancy_power`.
rule discrepancy_confusion:
    input:
        "results/figures/discrepancy_confusion.png",
        "results/figures/discrepancy_confusion.pdf",


rule discrepancy_power:
    input:
        "results/figures/discrepancy_power.png",
        "results/figures/discrepancy_power.pdf",


rule discrepancy_measured_before_after:
    input:
        "results/figures/discrepancy_measured_before_after.png",
        "results/figures/discrepancy_measured_before_after.pdf",


rule discrepancy_allan:
    input:
        "results/figures/discrepancy_allan.png",
        "results/figures/discrepancy_allan.pdf",


rule discrepancy_benchmark:
    """The benchmark: scores, rates, its summary, the confusion matrix and the power curves."""
    input:
        "results/discrepancy/benchmark/scores.csv",
        "results/discrepancy/benchmark/rates.csv",
        "results/discrepancy/benchmark/summary.csv",
        expand("results/figures/{f}.{ext}", f=("discrepancy_confusion", "discrepancy_power"), ext=("png", "pdf")),


rule discrepancy_measured:
    """The real recordings: both layers' reports and the two figures."""
    input:
        expand("results/discrepancy/measured/{recording}.json", recording=DISCREPANCY_RECORDINGS),
        expand("results/figures/{f}.{ext}", f=("discrepancy_measured_before_after", "discrepancy_allan"),
               ext=("png", "pdf")),


rule discrepancy:
    """The whole stage: benchmark, measured recordings, summary table and the four figures."""
    input:
        rules.discrepancy_benchmark.input,
        rules.discrepancy_measured.input,
        "results/discrepancy/summary.csv",
        "results/discrepancy/measured.csv",
