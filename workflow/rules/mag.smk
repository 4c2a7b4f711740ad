"""Stage 'mag': the magnetometer beside its peers on the real sessions.

Every configured session (SNU good1-3 with their rests, CK-Explorer's hand rotation, the
QMC5883L alone) calibrated by accelcal (ML ellipsoid, aligned to the accelerometer) and by
the peers as their authors run them (Magneto's Li-Griffiths ellipsoid, Dorveaux's iterative
method from tomisuarez2/MagnetometerCalibration, CK-Explorer's ellipsoid + alignment), judged
by what none optimises: the spread of |m| over the rests and of the dip between each rest's
field and its vertical; the SNU session-to-session scatter against the standard errors; the
Monte Carlo of the ellipsoid against the Cramér-Rao bound.  No claims (claims=False).
Config: the `mag` mapping (workflow/schemas/mag.schema.yaml).

Needs from common.smk: declare_stage, results, log_path, bench_path, figure_files,
figure_outputs, measured_data_dir, SMALL; the `measured` config's resources_dir.
"""

MAG = config["mag"]
#: {dataset: files} of the configured sessions (accelcal_repro.mag.sessions.FILES: its data
#: file, read without importing it).
MAG_TABLE = repro_table("mag_sessions.json")
MAG_DATASETS = dataset_files((MAG_TABLE[s]["dataset"], MAG_TABLE[s]["files"]) for s in MAG["sessions"])
MAG_STAGE = declare_stage(
    name="mag",
    figures=("mag_spread",),
    claims=False,
    tables=(("Real sessions: |m| spread and dip spread, raw, peers and accelcal", results("mag/sessions.csv")),
            ("Session-to-session scatter of accelcal's parameters against their s.e. (SNU good1-3)",
             results("mag/stability.csv")),
            ("Monte Carlo: RMS error / CRLB of the ellipsoid parameters", results("mag/montecarlo.csv")),
            ("Discrepancy loop: false positives and power at 3x MDE (simulated)", results("mag/loop_benchmark.csv")),
            ("Discrepancy loop on the real sessions", results("mag/loop_sessions.csv"))),
    summaries=(("Real sessions: each magnetometer calibration", summaries_path("mag_sessions")),),
)


rule mag_fetch:
    """Locate (shared copy) or download and verify (sha256) one dataset's files, as gyro_fetch."""
    priority: 100
    localrule: True
    output:
        results("mag/data/{mag_dataset}.json"),
    wildcard_constraints:
        mag_dataset="|".join(MAG_DATASETS),
    params:
        files=lambda w: list(MAG_DATASETS[w.mag_dataset]),
        data_dir=measured_data_dir(),
        resources_dir=config["measured"]["resources_dir"],
    log:
        log_path("mag/fetch_{mag_dataset}"),
    benchmark:
        bench_path("mag/fetch_{mag_dataset}"),
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,
    script:
        "../scripts/mag_fetch.py"


rule mag_sessions:
    """Every method on every configured session, and the SNU stability table."""
    input:
        manifests=expand(results("mag/data/{d}.json"), d=list(MAG_DATASETS)),
    output:
        table=results("mag/sessions.csv"),
        stability=results("mag/stability.csv"),
        summaries=summaries_path("mag_sessions"),
    params:
        mag=config_keys(MAG, "sessions"),
    log:
        log_path("mag/sessions"),
    benchmark:
        bench_path("mag/sessions"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,  # about 1 min
    script:
        "../scripts/mag_sessions.py"


rule mag_montecarlo:
    """The ML and the Li-Griffiths ellipsoid against the Cramér-Rao bound."""
    output:
        results("mag/montecarlo.csv"),
    params:
        mag=config_keys(MAG, "seed", "monte_carlo"),
    log:
        log_path("mag/montecarlo"),
    benchmark:
        bench_path("mag/montecarlo"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=20,  # default config: about 15 s
    script:
        "../scripts/mag_montecarlo.py"


rule mag_loop_benchmark:
    """The magnetometer loop on simulated sessions with one effect hidden: FPR and power."""
    output:
        cases=results("mag/loop_benchmark_cases.csv"),
        summary=results("mag/loop_benchmark.csv"),
    params:
        mag=config_keys(MAG, "seed", "loop"),
    log:
        log_path("mag/loop_benchmark"),
    benchmark:
        bench_path("mag/loop_benchmark"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=20,  # default config: 85 cases, about 30-60 s
    script:
        "../scripts/mag_loop_benchmark.py"


rule mag_loop_sessions:
    """Every real magnetometer session through the magnetometer loop."""
    input:
        manifests=expand(results("mag/data/{d}.json"), d=list(MAG_DATASETS)),
    output:
        results("mag/loop_sessions.csv"),
    params:
        mag=config_keys(MAG, "seed", "sessions", "loop"),
    log:
        log_path("mag/loop_sessions"),
    benchmark:
        bench_path("mag/loop_sessions"),
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,
    script:
        "../scripts/mag_loop_sessions.py"


rule mag_spread_figure:
    input:
        table=results("mag/sessions.csv"),
    output:
        **figure_outputs("mag_spread", "../report/mag_spread.rst", "Magnetometer"),
    log:
        log_path("mag/spread_figure"),
    benchmark:
        bench_path("mag/spread_figure"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/mag_figure.py"


rule mag:
    """The whole stage: tables and the figure."""
    input:
        results("mag/sessions.csv"),
        results("mag/stability.csv"),
        results("mag/montecarlo.csv"),
        results("mag/loop_benchmark.csv"),
        results("mag/loop_sessions.csv"),
        figure_files(*MAG_STAGE.figures),
