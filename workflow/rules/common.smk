"""Shared helpers of the workflow: config validation, the figure and claim registries,
log paths and default resources."""

import os
import re

import jsonschema
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate

#: Figure ids; every id is a target rule and results/figures/<id>.png|pdf.  Each stage
#: file appends its own (``FIGURES.append(...)``).
FIGURES = []
#: Stages that write results/claims/<stage>.csv; rule ``claims`` concatenates them.
CLAIM_STAGES = []


class ConfigError(WorkflowError):
    """A config that does not match the schema (one line: where and what)."""


def _config_error(where, what):
    # Snakemake prints a WorkflowError with its location in the workflow; the message
    # itself is one line: which config file(s), which key, what is wrong.
    files = [str(f) for f in (workflow.overwrite_configfiles or workflow.configfiles)]
    return ConfigError(f"invalid config ({', '.join(files) or 'no config file'}): {where}: {what}")


def _validate(cfg, schema, prefix=""):
    try:
        validate(cfg, schema, set_default=False)
    except WorkflowError as e:
        err = e.__context__  # validate() raises from inside `except ValidationError`
        if not isinstance(err, jsonschema.ValidationError):
            raise
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
    for key, (lo, hi) in cfg["burkhard"]["truth"].items():
        if lo > hi:
            raise _config_error(f"burkhard.truth.{key}", f"low end {lo} exceeds high end {hi}")
    timing = cfg["foundation"]["timing"]
    if timing["headline_interleave"] not in timing["interleavings"]:
        raise _config_error("foundation.timing.headline_interleave",
                            f"{timing['headline_interleave']!r} is not in interleavings {timing['interleavings']}")


def log_path(name):
    """Log file of a job: results/logs/<name>.log (results/ is generated, not versioned)."""
    return f"results/logs/{name}.log"


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
