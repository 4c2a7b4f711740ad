"""Shared helpers of the workflow: config validation, output paths, what each stage adds
to the final targets, and default resources."""

import json
import os
import re
import sys
from dataclasses import dataclass

import jsonschema
import yaml
from snakemake.exceptions import WorkflowError

# Neither accelcal nor the reproductions (accelcal_repro) are imported while the workflow is
# parsed, only by its jobs: the estimator names a config may list come from the registry's
# table read as JSON (workflow/scripts/_registry_table.py, standard library only), which the
# stage files import from the scripts' folder (tests/test_workflow_parse.py holds this).
# (beside this file, not the top Snakefile: a test's throwaway Snakefile includes it alone)
WORKFLOW_DIR = os.path.dirname(str(workflow.current_basedir))  # workflow/
sys.path.insert(0, os.path.join(WORKFLOW_DIR, "scripts"))
from _registry_table import accelerometer_estimators



# --------------------------------------------------------------------------- reproduction tables
# The tables of the reproductions that the DAG needs (datasets and files of the sessions)
# live as data files in src/accelcal_repro/data/, read by their modules and, here, as plain
# JSON: parsing the workflow (every snakemake call, every SLURM job) imports no reproduction.
REPRO_DATA = os.path.join(os.path.dirname(WORKFLOW_DIR), "src", "accelcal_repro", "data")


def repro_table(name):
    """A table of src/accelcal_repro/data (the file its module reads)."""
    with open(os.path.join(REPRO_DATA, name), encoding="utf-8") as f:
        return json.load(f)


def dataset_files(pairs):
    """``{dataset: [files]}`` of ``(dataset, files)`` pairs: each file once, in first-seen order."""
    out = {}
    for dataset, files in pairs:
        have = out.setdefault(dataset, [])
        have += [f for f in files if f and f not in have]
    return out

# --------------------------------------------------------------------------- output paths
# As pypsa-eur's resources()/logs(): the folder layout is decided here, the rules name files.


def results(path):
    """An output of the workflow: results/<path> (generated, not versioned; results/README.md)."""
    return f"results/{path}"


def log_path(name):
    """Log file of a job: results/logs/<name>.log."""
    return results(f"logs/{name}.log")


def bench_path(name):
    """Benchmark file of a job (wall time s, max_rss MB, ...): results/benchmarks/<name>.tsv.
    The first path component is the stage; the report sums the wall times per stage."""
    return results(f"benchmarks/{name}.tsv")


def figure_files(*figure_ids):
    """results/figures/<id>.png and .pdf of each figure id."""
    return [results(f"figures/{fid}.{ext}") for fid in figure_ids for ext in ("png", "pdf")]


# --------------------------------------------------------------------------- config per key
# As pypsa-eur's config_provider: a rule's params hold only the keys its code reads, so that
# --rerun-triggers params reruns it only when one of those changes (a new claim threshold
# reruns the claims job, not the Monte Carlo that the claims are computed from).


def config_keys(section, *paths):
    """The keys ``paths`` of a config ``section`` (``"claims.gyro_convergence_s"`` for a nested
    key), in a mapping of the same shape.  A path the section does not have is left out: the
    code that reads it applies its documented default, as it would with the whole section."""
    out = {}
    for path in paths:
        *parents, leaf = path.split(".")
        src, dst = section, out
        for key in parents:
            if not isinstance(src.get(key), dict):
                break
            src, dst = src[key], dst.setdefault(key, {})
        else:
            if leaf in src:
                dst[leaf] = src[leaf]
    return out


#: Outputs one stage makes and another reads (measured -> discrepancy).
MEASURED_CSV = results("measured/{recording}.csv")  # a recording as the canonical CSV of the CLI
MEASURED_SUMMARY = results("measured/summary.csv")


#: The numba disk cache filled once (rule kernel_cache, workflow/rules/kernels.smk): an input
#: of every job that calls compiled kernels, so that they load them instead of each
#: compiling them (or waiting for one another's compilation) at the start of a fresh clone.
KERNEL_CACHE = results("timing/kernel_cache.csv")


def measured_data_dir():
    """The shared copy of the measured data (config measured.data_dir; a relative path is
    taken from the project root, so that `--directory elsewhere` still finds ../shared/data)."""
    return os.path.normpath(os.path.join(workflow.basedir, config["measured"]["data_dir"]))


# --------------------------------------------------------------------------- final targets


@dataclass(frozen=True)
class Stage:
    """What one stage adds to the final targets, declared once in its rule file (:func:`declare_stage`).

    ``figures``: figure ids (each a rule target and results/figures/<id>.png|pdf);
    ``claims``: whether it writes results/claims/<name>.csv for the ledger; ``tables``:
    (title, path) of its summary tables shown in the report, in the stage's section;
    ``summaries``: (title, path) of its results' summaries files (accelcal.summary.write_summaries),
    shown there before the tables, each result by its Summary's as_html.
    """

    name: str
    figures: tuple = ()
    claims: bool = True
    tables: tuple = ()
    summaries: tuple = ()


def declare_stage(name, figures=(), claims=True, tables=(), summaries=()):
    """The :class:`Stage` ``name``, and each of its figure ids as a target rule of its own:
    `snakemake <id>` makes its PNG and PDF (target only: no job, no log)."""
    stage = Stage(name, tuple(figures), claims, tuple(tables), tuple(summaries))
    for fid in stage.figures:

        rule:
            name:
                fid
            localrule: True
            input:
                figure_files(fid),

    return stage


# STAGES (the Snakefile: the stage declarations in the order of the ledger and the report)
# is read only in functions, called once every rule file is included.


def figure_ids():
    """Every stage's figure ids."""
    return [fid for stage in STAGES for fid in stage.figures]


def claim_stages():
    """The stages that write results/claims/<stage>.csv, in the ledger's order."""
    return [stage.name for stage in STAGES if stage.claims]


def report_tables():
    """(section, title, path) of every stage's summary tables, in the report's order."""
    return [(stage.name, title, path) for stage in STAGES for title, path in stage.tables]


def report_summaries():
    """(section, title, path) of every stage's summaries files, in the report's order."""
    return [(stage.name, title, path) for stage in STAGES for title, path in stage.summaries]


def summaries_path(name):
    """results/summaries/<name>.json: the Summaries of one job's results, for the report."""
    return results(f"summaries/{name}.json")


def get_final_output():
    """The targets of `snakemake all`: every figure (PNG and PDF), the claims ledger and the report."""
    return figure_files(*figure_ids()) + [results("claims.csv"), results("report.html")]


# --------------------------------------------------------------------------- config


class ConfigError(WorkflowError):
    """A config that does not match the schema (one line: where and what)."""


def _config_error(where, what):
    # Snakemake prints a WorkflowError with its location in the workflow; the message
    # itself is one line: which config file(s), which key, what is wrong.
    files = [str(f) for f in (workflow.overwrite_configfiles or workflow.configfiles)]
    return ConfigError(f"invalid config ({', '.join(files) or 'no config file'}): {where}: {what}")


_SCHEMAS = {}


def _schema(path):
    """A schema file, parsed once per process, by libyaml where PyYAML has it.  Every
    snakemake call (dry runs, each SLURM job) parses the Snakefile and with it the
    schemas: snakemake.utils.validate's pure-Python YAML took ~0.3 s of CPU of that."""
    path = os.path.join(workflow.basedir, path) if not os.path.isabs(path) else path
    if path not in _SCHEMAS:
        with open(path, encoding="utf-8") as f:
            _SCHEMAS[path] = yaml.load(f, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    return _SCHEMAS[path]


def _validate(cfg, schema_path, prefix=""):
    """``cfg`` against a JSON schema (draft 2020-12, as snakemake.utils.validate; the
    schemas refer only within themselves): the first error as one line."""
    try:
        jsonschema.Draft202012Validator(_schema(schema_path)).validate(cfg)
    except jsonschema.ValidationError as err:
        where = ".".join([prefix] * bool(prefix) + [str(p) for p in err.absolute_path]) or "(top level)"
        raise _config_error(where, err.message) from None


def check_config(cfg, schema):
    """Validate ``cfg`` against the JSON schema, each stage's section against the stage's
    own schema (``workflow/schemas/<key>.schema.yaml``, where one exists).  The rules a
    schema cannot express are the stages' own (:func:`check_section`, in each rule file),
    run when the file is included, once every section passed its schema."""
    _validate(cfg, schema)
    schemas = os.path.join(workflow.basedir, "workflow", "schemas")
    for key in sorted(cfg):
        stage_schema = os.path.join(schemas, f"{key}.schema.yaml")
        if os.path.exists(stage_schema):
            _validate(cfg[key], stage_schema, prefix=key)
            _check_ranges(cfg[key], stage_schema, prefix=key)


def check_section(key, check):
    """A stage's rules that its schema cannot express: ``check(section, config)`` raises a
    one-line ConfigError naming the key (:func:`_config_error`)."""
    check(config[key], config)


def _ranges(schema, defs, path=()):
    """Key paths of the [low, high] ranges of a schema: properties that refer (directly
    or through another definition) to ``#/$defs/range``."""
    for name, sub in schema.get("properties", {}).items():
        ref = sub
        while ref.get("$ref", "").startswith("#/$defs/") and ref["$ref"] != "#/$defs/range":
            ref = defs[ref["$ref"].removeprefix("#/$defs/")]
        if ref.get("$ref") == "#/$defs/range":
            yield path + (name,)
        yield from _ranges(sub, defs, path + (name,))


def _check_ranges(section, schema_path, prefix):
    """Every [low, high] range of a stage section (found in its schema) has low <= high."""
    schema = _schema(schema_path)
    for path in _ranges(schema, schema.get("$defs", {})):
        value = section
        for k in path:
            value = value[k]
        lo, hi = value
        if lo > hi:
            raise _config_error(".".join((prefix, *path)), f"low end {lo} exceeds high end {hi}")


def _check_names(names, known, where, what):
    """Every name of a config list is one of ``known`` (the schemas do not restate the
    registries: the names are checked here, against the code)."""
    for i, name in enumerate(names):
        if name not in known:
            raise _config_error(f"{where}.{i}", f"{name!r} is not {what}; known: {', '.join(known)}")


def _check_estimators(names, where):
    """Every name is a registered accelerometer estimator (accelcal.registry's table)."""
    _check_names(names, list(accelerometer_estimators()), where, "a registered estimator")


def figure_outputs(figure_id, caption, category):
    """PNG + PDF of a figure, both in the Snakemake report with the figure's caption."""
    return {
        ext: report(path, caption=caption, category=category, labels={"figure": figure_id, "format": ext.upper()})
        for ext, path in zip(("png", "pdf"), figure_files(figure_id))
    }


#: Resources of small jobs (plots, gathering tables): mem_mb [MB], runtime [min].
SMALL = {"mem_mb": 1000, "runtime": 10}


def stage_figures(stage, inputs, category, script_path, params=None, captions=None, resources=SMALL):
    """Rule ``<stage>_figures``: one job draws every figure of ``stage``.

    A figure takes well under a second to draw but about 2 s of CPU to start (Python, pandas,
    pyplot, the stage's package): one job per figure spent most of its time starting.  Each
    figure id stays a target (declare_stage), as does its PNG or PDF path; asking for one
    runs this job, which draws its siblings too.  ``inputs`` maps each figure id to its named
    inputs; the job's input keys are ``<id>__<key>`` and its outputs ``<id>__png`` and
    ``<id>__pdf``, which the script takes apart with _helpers.stage_figures.  ``captions``:
    a figure's caption file where it is not ../report/<id>.rst."""
    captions = captions or {}

    rule:
        name:
            f"{stage.name}_figures"
        input:
            **{f"{fid}__{key}": path for fid in stage.figures for key, path in inputs[fid].items()},
        output:
            **{f"{fid}__{ext}": path for fid in stage.figures
               for ext, path in figure_outputs(fid, captions.get(fid, f"../report/{fid}.rst"), category).items()},
        params:
            figures=list(stage.figures),
            **(params or {}),
        log:
            log_path(f"{stage.name}/figures"),
        benchmark:
            bench_path(f"{stage.name}/figures"),
        threads: 1
        resources:
            **resources,
        script:
            script_path  # not `script`: Snakemake's rule body calls a function of that name
