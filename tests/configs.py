"""The workflow's configs as Snakemake builds them, for tests that read them directly."""

import copy
import functools
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CONFIG = REPO / "config" / "config.yaml"
CI_CONFIG = REPO / "config" / "ci.yaml"


def _extend(base: dict, overlay: dict) -> dict:
    # snakemake.utils.update_config: a mapping merges key by key, anything else replaces
    for key, value in overlay.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            _extend(base[key], value)
        else:
            base[key] = value
    return base


@functools.lru_cache(maxsize=None)
def _parsed(path: Path):
    # Parsed once per process, by libyaml where PyYAML has it: the config tests build a
    # few dozen configs at collection, in every test worker.
    return yaml.load(path.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def load_config(overlay: str | Path | None = None) -> dict:
    """config/config.yaml extended by ``overlay`` (a file of config/, e.g. ``"ci.yaml"``),
    as ``snakemake --configfile`` does (a new copy at every call)."""
    config = copy.deepcopy(_parsed(DEFAULT_CONFIG))
    if overlay is not None and Path(overlay).name != DEFAULT_CONFIG.name:
        _extend(config, copy.deepcopy(_parsed(REPO / "config" / overlay)) or {})
    return config


def ci_config() -> dict:
    """The CI configuration (config/config.yaml + config/ci.yaml)."""
    return load_config(CI_CONFIG.name)
