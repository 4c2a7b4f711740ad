"""Shared helpers of the workflow: config validation, output paths, what each stage adds
to the final targets, and default resources."""

import os
import re
from dataclasses import dataclass

import jsonschema
import yaml
from snakemake.exceptions import WorkflowError


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
    (title, path) of its summary tables shown in the report, in the stage's section.
    """

    name: str
    figures: tuple = ()
    claims: bool = True
    tables: tuple = ()


def declare_stage(name, figures=(), claims=True, tables=()):
    """The :class:`Stage` ``name``, and each of its figure ids as a target rule of its own:
    `snakemake <id>` makes its PNG and PDF (target only: no job, no log)."""
    stage = Stage(name, tuple(figures), claims, tuple(tables))
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
    own schema (``workflow/schemas/<key>.schema.yaml``, where one exists), then the rules a
    schema cannot express (which may compare sections, so they run once all are valid)."""
    _validate(cfg, schema)
    schemas = os.path.join(workflow.basedir, "workflow", "schemas")
    for key in sorted(cfg):
        stage_schema = os.path.join(schemas, f"{key}.schema.yaml")
        if os.path.exists(stage_schema):
            _validate(cfg[key], stage_schema, prefix=key)
            _check_ranges(cfg[key], stage_schema, prefix=key)
    for key in sorted(cfg):
        if key in STAGE_RULES:
            STAGE_RULES[key](cfg[key], cfg)


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


def _check_batista2011(b, cfg):
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


def _check_tereshkov(t, cfg):
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


def _check_measured(m, cfg):
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


def _check_burkhard2024(b, cfg):
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


def _check_benchmark(b, cfg):
    if b["compile_calls"] != "all":
        from accelcal_repro.first_calls import FIRST_CALLS

        _check_names(b["compile_calls"], FIRST_CALLS, "benchmark.compile_calls", "a first call of a compiled kernel")


def _check_gyro(g, cfg):
    # IMU-TK's run from source is read, never made, by the workflow: the file must exist
    if g["imutk_run"] and not os.path.isfile(os.path.join(workflow.basedir, g["imutk_run"])):
        raise _config_error("gyro.imutk_run", f"{g['imutk_run']}: no such file (tools/gyro_peers.py run-imutk "
                            "writes it; null compares with IMU-TK's published results only)")
    from accelcal_repro.gyro.sessions import SESSIONS

    _check_names(g["sessions"], list(SESSIONS), "gyro.sessions", "a gyro session")


def _check_noise(n, cfg):
    names = [c["name"] for c in n["coverage"]["configurations"]]
    if len(set(names)) != len(names):
        raise _config_error("noise.coverage.configurations", "configuration names must be distinct")


#: Rules a stage's schema cannot express, run once every section passed its schema:
#: ``rule(section, config)``, a one-line ConfigError naming the key.
STAGE_RULES = {"batista2011": _check_batista2011, "tereshkov": _check_tereshkov, "measured": _check_measured,
               "burkhard2024": _check_burkhard2024, "discrepancy": _check_discrepancy,
               "benchmark": _check_benchmark, "gyro": _check_gyro, "noise": _check_noise}


def figure_outputs(figure_id, caption, category):
    """PNG + PDF of a figure, both in the Snakemake report with the figure's caption."""
    return {
        ext: report(path, caption=caption, category=category, labels={"figure": figure_id, "format": ext.upper()})
        for ext, path in zip(("png", "pdf"), figure_files(figure_id))
    }


#: Resources of small jobs (plots, gathering tables): mem_mb [MB], runtime [min].
SMALL = {"mem_mb": 1000, "runtime": 10}
