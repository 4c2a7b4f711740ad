"""Shared helpers of the workflow: config validation, the figure and claim registries,
log paths and default resources."""

import os
import re

import jsonschema
import yaml
from snakemake.exceptions import WorkflowError

#: Figure ids; every id is a target rule and results/figures/<id>.png|pdf.  Each stage
#: file appends its own (``FIGURES.append(...)``).
FIGURES = []
#: Stages that write results/claims/<stage>.csv; rule ``claims`` concatenates them.
CLAIM_STAGES = []
#: Summary tables shown in results/report.html: (section, title, path).  A stage appends
#: its own, so the report asks only for tables the DAG knows how to make.
REPORT_TABLES = []


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
    own schema (``workflow/schemas/<key>.schema.yaml``, where one exists), then the rules a
    schema cannot express."""
    _validate(cfg, schema)
    schemas = os.path.join(workflow.basedir, "workflow", "schemas")
    for key in sorted(cfg):
        stage_schema = os.path.join(schemas, f"{key}.schema.yaml")
        if os.path.exists(stage_schema):
            _validate(cfg[key], stage_schema, prefix=key)
            _check_ranges(cfg[key], stage_schema, prefix=key)
            if key in STAGE_RULES:
                STAGE_RULES[key](cfg[key])


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


def _check_batista2011(b):
    s = b["calibration"]["schedule"]
    # accelcal_repro.batista2011.trajectory.StepSchedule: the window must miss the transition
    if not s["transition_s"] <= s["window_start_s"] <= s["step_s"] - s["window_s"]:
        raise _config_error("batista2011.calibration.schedule.window_start_s",
                            f"the data window {s['window_start_s']}-{s['window_start_s'] + s['window_s']} s "
                            f"must lie in the static part {s['transition_s']}-{s['step_s']} s of each step")
    for part in ("calibration", "filter"):
        if b[part]["jobs"] > b[part]["runs"]:
            raise _config_error(f"batista2011.{part}.jobs",
                                f"{b[part]['jobs']} jobs for {b[part]['runs']} runs would leave a job without runs")
    f = b["filter"]
    if f["steady_from_s"] >= f["duration_s"]:
        raise _config_error("batista2011.filter.steady_from_s",
                            f"{f['steady_from_s']} s leaves no steady state in a run of filter.duration_s = "
                            f"{f['duration_s']} s")
    # the observability runs use the filter's time grid; a longer window would be cut silently
    if b["observability"]["gramian_window_s"] > f["duration_s"]:
        raise _config_error("batista2011.observability.gramian_window_s",
                            f"{b['observability']['gramian_window_s']} s exceeds the run, filter.duration_s = "
                            f"{f['duration_s']} s")


def _check_tereshkov(t):
    for part in ("monte_carlo", "sweep", "comparison"):
        start, duration = t[part]["steady_state_from_s"], t[part]["duration_s"]
        if start >= duration:
            raise _config_error(f"tereshkov.{part}.steady_state_from_s",
                                f"{start} s leaves no steady state in a run of {part}.duration_s = {duration} s")
    # a job holds the runs r with r % jobs == job of every scenario it simulates
    for part, scenarios in (("monte_carlo", ("field", "straight", "artificial")), ("sweep", None)):
        runs = {sc: t["scenarios"][sc]["runs"] for sc in scenarios} if scenarios else {"sweep": t["sweep"]["runs"]}
        fewest = min(runs, key=runs.get)
        if t[part]["jobs"] > runs[fewest]:
            raise _config_error(f"tereshkov.{part}.jobs",
                                f"{t[part]['jobs']} jobs for the {runs[fewest]} runs of {fewest} would leave a job "
                                "without runs")
    e = t["estimator"]
    if e["turn_rate_dps"] <= e["straight_rate_dps"]:
        raise _config_error("tereshkov.estimator.turn_rate_dps",
                            f"{e['turn_rate_dps']} must exceed straight_rate_dps = {e['straight_rate_dps']}")
    # the external specific force is differenced GNSS velocity interpolated to the IMU samples
    for where in ("imu.rate_hz", "comparison.imu_rate_hz"):
        part, key = where.split(".")
        rate = t[part][key]
        if t["gnss"]["rate_hz"] > rate:
            raise _config_error("tereshkov.gnss.rate_hz",
                                f"{t['gnss']['rate_hz']} Hz exceeds the IMU rate {where} = {rate} Hz")


def _check_names(names, known, where, what):
    """Every name of a config list is one of ``known`` (the schemas do not restate the
    registries: the names are checked here, against the code)."""
    for i, name in enumerate(names):
        if name not in known:
            raise _config_error(f"{where}.{i}", f"{name!r} is not {what}; known: {', '.join(known)}")


def _check_estimators(names, where):
    """Every name is a registered accelerometer estimator (accelcal.registry)."""
    from accelcal.registry import estimators

    _check_names(names, [e.name for e in estimators("accelerometer")], where, "a registered estimator")


def _check_measured(m):
    for name, rec in m["recordings"].items():
        _check_estimators(rec["estimators"], f"measured.recordings.{name}.estimators")
    # The six static positions of the Ferraris session list (accelcal_repro.measured.sources.
    # FERRARIS_STATIC) are fewer than the full models need (accelcal.registry: min_poses).
    from accelcal.registry import ESTIMATORS
    from accelcal_repro.measured.sources import FERRARIS_STATIC

    ferraris = m["recordings"].get("imucal_ferraris")
    if ferraris and ferraris["pose_selection"] == "section_list":
        short = [e for e in ferraris["estimators"] if ESTIMATORS[e].min_poses > len(FERRARIS_STATIC)]
        if short:
            need = max(ESTIMATORS[e].min_poses for e in short)
            raise _config_error("measured.recordings.imucal_ferraris.estimators",
                                f"{', '.join(short)} need at least {need} poses, pose_selection 'section_list' "
                                f"gives the session's {len(FERRARIS_STATIC)} static positions (bias-only "
                                "estimators only)")


def _check_burkhard2024(b):
    for name, exp in b["experiments"].items():
        _check_estimators(exp["methods"], f"burkhard2024.experiments.{name}.methods")
    timing = b["timing"]
    for key, among in (("headline_interleave", "interleavings"), ("headline_n_poses", "n_poses")):
        if timing[key] not in timing[among]:
            raise _config_error(f"burkhard2024.timing.{key}", f"{timing[key]!r} is not in {among} {timing[among]}")
    # the Fig. 1(a) claims are judged over the paper's noise range: it must hold a grid level
    lo, hi = b["claims"]["paper_noise_range"]
    if not any(lo <= s <= hi for s in b["experiments"]["fig1a"]["noise_std"]):
        raise _config_error("burkhard2024.experiments.fig1a.noise_std",
                            f"no noise level in claims.paper_noise_range [{lo}, {hi}]")


def _check_benchmark(b):
    if b["compile_calls"] != "all":
        from accelcal_repro.first_calls import FIRST_CALLS

        _check_names(b["compile_calls"], FIRST_CALLS, "benchmark.compile_calls", "a first call of a compiled kernel")


#: Rules a stage's schema cannot express, run after the schema accepted the section.
STAGE_RULES = {"batista2011": _check_batista2011, "tereshkov": _check_tereshkov, "measured": _check_measured,
               "burkhard2024": _check_burkhard2024, "benchmark": _check_benchmark}


def log_path(name):
    """Log file of a job: results/logs/<name>.log (results/ is generated, not versioned)."""
    return f"results/logs/{name}.log"


def bench_path(name):
    """Benchmark file of a job (wall time s, max_rss MB, ...): results/benchmarks/<name>.tsv.
    The first path component is the stage; the report sums the wall times per stage."""
    return f"results/benchmarks/{name}.tsv"


def figure_outputs(figure_id, caption, category):
    """PNG + PDF of a figure, both in the Snakemake report with the figure's caption."""
    return {
        "png": report(f"results/figures/{figure_id}.png", caption=caption, category=category,
                      labels={"figure": figure_id, "format": "PNG"}),
        "pdf": report(f"results/figures/{figure_id}.pdf", caption=caption, category=category,
                      labels={"figure": figure_id, "format": "PDF"}),
    }


def noise_key(x):
    """File-name key of a noise level, e.g. 1e-07, 0.001 (exact: 12 significant digits)."""
    return format(float(x), ".12g")


#: Resources of small jobs (plots, gathering tables): mem_mb [MB], runtime [min].
SMALL = {"mem_mb": 1000, "runtime": 10}
