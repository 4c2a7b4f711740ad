"""Stage 'noise': the noise analysis of a static recording (what `accelcal noise` runs) on the
2.78 h ADIS16405 record against its datasheet, with the Kalibr and OpenVINS files it
exports, and the coverage of its term intervals on simulated records with known terms.

* ``noise_adis``: the record (located or downloaded by ``discrepancy_adis_fetch``, whose
  manifest it reads) through :func:`accelcal.noise.analyse_noise`: the report JSON, Kalibr's
  ``imu.yaml``, OpenVINS's ``kalibr_imu_chain.yaml``, the table against the datasheet and
  the figure ``noise_adis16405``.
* ``noise_coverage``: per configuration, simulated records analysed and the coverage of
  every term's interval counted; ``noise_coverage_table`` gathers them.
* ``noise_claims``: results/claims/noise.csv.

Config: section ``noise`` (its cross-key rule: _check_noise, common.smk).
Needs from common.smk: declare_stage, results, log_path, bench_path, figure_outputs,
figure_files, SMALL.
"""

import re

NOISE = config["noise"]


# The stage's config rules that its schema cannot express (one line naming the key).
def _check_noise(n, cfg):
    names = [c["name"] for c in n["coverage"]["configurations"]]
    if len(set(names)) != len(names):
        raise _config_error("noise.coverage.configurations", "configuration names must be distinct")


check_section("noise", _check_noise)
NOISE_DIR = results("noise")
NOISE_ADIS_DIR = f"{NOISE_DIR}/adis16405"
NOISE_DATASHEET = f"{NOISE_ADIS_DIR}/datasheet.csv"
NOISE_COVERAGE = f"{NOISE_DIR}/coverage.csv"
NOISE_CONFIGURATIONS = [c["name"] for c in NOISE["coverage"]["configurations"]]
#: The ADIS16405 record's manifest, written by discrepancy_adis_fetch (discrepancy.smk).
NOISE_ADIS_MANIFEST = results("discrepancy/adis/data.json")

NOISE_STAGE = declare_stage(
    name="noise",
    figures=("noise_adis16405",),
    tables=(("ADIS16405 (2.78 h static record): noise terms against the datasheet", NOISE_DATASHEET),
            ("Coverage of the term intervals on simulated records with known terms", NOISE_COVERAGE)),
    summaries=(("ADIS16405: the noise report (accelcal noise)", summaries_path("noise_adis16405")),),
)


wildcard_constraints:
    configuration="|".join(re.escape(c) for c in NOISE_CONFIGURATIONS),


rule noise_adis:
    """The ADIS16405 record's noise: report, exports, the datasheet table and the figure."""
    input:
        manifest=NOISE_ADIS_MANIFEST,
    output:
        report=f"{NOISE_ADIS_DIR}/noise.json",
        kalibr=f"{NOISE_ADIS_DIR}/imu.yaml",
        openvins=f"{NOISE_ADIS_DIR}/kalibr_imu_chain.yaml",
        datasheet=NOISE_DATASHEET,
        summaries=summaries_path("noise_adis16405"),
        **figure_outputs("noise_adis16405", "../report/noise_adis16405.rst", "Noise"),
    params:
        file="adis_16405_imu1.rda",
        adis=NOISE["adis"],
    log:
        log_path("noise/adis"),
    benchmark:
        bench_path("noise/adis"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,  # reading the R file ~0.7 s, the analysis ~0.5 s, the figure ~2 s
    script:
        "../scripts/noise_adis.py"


rule noise_coverage:
    """Simulated records of one configuration: the coverage of every term's interval."""
    output:
        f"{NOISE_DIR}/coverage/{{configuration}}.csv",
    params:
        terms=lambda w: NOISE["coverage"]["configurations"][NOISE_CONFIGURATIONS.index(w.configuration)],
        index=lambda w: NOISE_CONFIGURATIONS.index(w.configuration),
        coverage=NOISE["coverage"],
    log:
        log_path("noise/coverage_{configuration}"),
    benchmark:
        bench_path("noise/coverage_{configuration}"),
    threads: 1
    resources:
        mem_mb=1000,
        runtime=15,  # default config: 30 records of 2^17 samples, about 0.2 s each
    script:
        "../scripts/noise_coverage.py"


rule noise_coverage_table:
    """Gather the configurations: results/noise/coverage.csv."""
    input:
        expand(f"{NOISE_DIR}/coverage/{{configuration}}.csv", configuration=NOISE_CONFIGURATIONS),
    output:
        NOISE_COVERAGE,
    log:
        log_path("noise/coverage_table"),
    benchmark:
        bench_path("noise/coverage_table"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/noise_coverage_table.py"


rule noise_claims:
    """Ledger rows: the datasheet's four figures, and the coverage of the intervals."""
    input:
        datasheet=NOISE_DATASHEET,
        coverage=NOISE_COVERAGE,
    output:
        results("claims/noise.csv"),
    params:
        claims=NOISE["claims"],
        level=NOISE["coverage"]["level"],
    log:
        log_path("noise/claims"),
    benchmark:
        bench_path("noise/claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/noise_claims.py"


rule noise:
    """The whole stage: the ADIS16405 table, exports and figure, the coverage table and the claims."""
    input:
        rules.noise_adis.output,
        NOISE_COVERAGE,
        results("claims/noise.csv"),
        figure_files(*NOISE_STAGE.figures),
