"""accelcal: reproducible workflow for Burkhard et al. (2024), Batista et al. (2011), Tereshkov, and the
project's own stages (measured data, discrepancy, gyroscope, noise, benchmark).

    .venv/bin/snakemake all                               # paper scale (profiles/default)
    .venv/bin/snakemake all --configfile config/ci.yaml   # reduced sizes (tests, CI)
    .venv/bin/snakemake burkhard2024_fig1a                # a figure (every figure id is a target; one job
                                                          # per stage draws it with the stage's other figures)

Layout (snakemake-workflows style): this file loads and validates the config, then
includes one rule file per stage from workflow/rules/; the final targets are gathered from
the stages' declarations (get_final_output, workflow/rules/common.smk).  Thin scripts in
workflow/scripts/ call the library (src/accelcal/).  Outputs go to results/
(see results/README.md), logs to results/logs/.  The measured data are fetched by jobs
(the shared copy, else a verified download): the simulation stages need none.
"""

import os

from snakemake.utils import min_version

min_version("9.0")


include: "workflow/rules/scheduler.smk"


# One BLAS thread per job: the jobs are the parallelism (--cores, or one SLURM task each).
# With a multi-threaded BLAS in each of two jobs on two cores, their threads spin for each
# other's core: the discrepancy benchmark's detection ran 22x slower per job that way.
# Inherited by every job (and re-read by each SLURM job); a value the user set is kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")


# The default config, next to this file (so --directory elsewhere still finds it).
# --configfile FILE extends it key by key; add --replace-workflow-config to replace it.
configfile: os.path.join(workflow.basedir, "config", "config.yaml")


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"


# Fail on a broken config before any job runs, with one line naming the key.
check_config(config, "workflow/schemas/config.schema.yaml")


# One rule file per stage; each declares what it adds to the final targets (declare_stage:
# figures, each also a target of its own, claims, report tables).  The rules that gather
# them (claims, report, all) read the declarations in functions, once every file is
# included, so the order of the includes does not matter.
include: "workflow/rules/kernels.smk"
include: "workflow/rules/burkhard2024.smk"
include: "workflow/rules/batista2011.smk"
include: "workflow/rules/tereshkov.smk"
include: "workflow/rules/measured.smk"
include: "workflow/rules/discrepancy.smk"
include: "workflow/rules/gyro.smk"
include: "workflow/rules/noise.smk"
include: "workflow/rules/mag.smk"
include: "workflow/rules/benchmark.smk"
include: "workflow/rules/claims.smk"
include: "workflow/rules/report.smk"


#: The stages, in the order of the claims ledger and of the tables in each report section.
STAGES = (BURKHARD_STAGE, BATISTA_STAGE, TERESHKOV_STAGE, MEASURED_STAGE, DISCREPANCY_STAGE, GYRO_STAGE, NOISE_STAGE,
          MAG_STAGE, BENCHMARK_STAGE)


rule all:
    """Every figure, the claims ledger and the report (target only: no job, hence no log or resources)."""
    default_target: True
    localrule: True
    input:
        get_final_output(),
