"""The simulation grids of Burkhard et al. (2024), Fig. 1, as experiments.

An *experiment* (one panel of Fig. 1, or an analysis beyond the paper) is a product
grid: one data set (``data_model``: ``'full'`` = generated with the drawn ``M ≠ I``,
``'bias'`` = generated with ``M = I``), pose counts, noise levels, errors in the assumed
g and the methods to run.  Experiments share grid points: the Fig. 1(a) point at
24 poses and the noise of Fig. 1(b)-(e) is the same data-generating setting.

The workflow merges the experiments into one Monte Carlo job per grid point
``(n_poses, noise_std, g_error)`` (``workflow/scripts/_burkhard2024_points.py``, which
reads the registry's table as data so that parsing imports nothing); a method is left out
at a pose count below its minimum q + 1 (10 full, 4 bias-only).
:func:`select` picks an experiment's rows back out of a summary table.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import pandas as pd

from ..montecarlo import DATA_MODELS, METHODS, min_poses

#: The experiments, in the order of the paper's figure (plus the CRLB panel and the limit).
EXPERIMENTS = ("fig1a", "efficiency", "fig1b", "fig1cd", "fig1e", "lls_limit")


@dataclass(frozen=True)
class Experiment:
    """One product grid: ``data_model`` × ``n_poses`` × ``noise_std`` × ``g_error`` × ``methods``."""

    name: str
    data_model: str
    n_poses: tuple[int, ...]
    noise_std: tuple[float, ...]
    g_error: tuple[float, ...]
    methods: tuple[str, ...]

    def __post_init__(self):
        if self.data_model not in DATA_MODELS:
            raise ValueError(f"experiment {self.name}: data_model must be one of {DATA_MODELS}")
        unknown = [m for m in self.methods if m not in METHODS]
        if unknown:
            raise ValueError(f"experiment {self.name}: unknown method(s) {unknown}")
        if not (self.n_poses and self.noise_std and self.g_error and self.methods):
            raise ValueError(f"experiment {self.name}: every axis of the grid needs at least one value")
        usable = [m for m in self.methods if any(n >= min_poses(m) for n in self.n_poses)]
        if len(usable) < len(self.methods):
            raise ValueError(f"experiment {self.name}: method(s) {sorted(set(self.methods) - set(usable))} need "
                             f"more poses than any of {list(self.n_poses)}")


def experiments_from_config(cfg: Mapping) -> dict[str, Experiment]:
    """``{name: Experiment}`` from the ``experiments`` mapping of the stage config."""
    out = {}
    for name, e in cfg.items():
        out[name] = Experiment(name=name, data_model=e["data_model"],
                               n_poses=tuple(int(n) for n in e["n_poses"]),
                               noise_std=tuple(float(s) for s in e["noise_std"]),
                               g_error=tuple(float(x) for x in e["g_error"]),
                               methods=tuple(m for m in METHODS if m in e["methods"]))
    return out


def select(table: pd.DataFrame, experiment: Experiment) -> pd.DataFrame:
    """The rows of a summary (or tidy) table that belong to ``experiment``."""
    e = experiment
    sel = (table["data_model"].eq(e.data_model) & table["n_poses"].isin(e.n_poses)
           & table["noise_std"].isin(e.noise_std) & table["g_error"].isin(e.g_error))
    if "method" in table:
        sel &= table["method"].isin(e.methods)
    return table[sel].reset_index(drop=True)


__all__ = ["EXPERIMENTS", "Experiment", "experiments_from_config", "select"]
