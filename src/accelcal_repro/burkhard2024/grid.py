"""The simulation grids of Burkhard et al. (2024), Fig. 1, as experiments over grid points.

An *experiment* (one panel of Fig. 1, or an analysis beyond the paper) is a product
grid: one data set (``data_model``: ``'full'`` = generated with the drawn ``M ≠ I``,
``'bias'`` = generated with ``M = I``), pose counts, noise levels, errors in the assumed
g and the methods to run.  Experiments share grid points: the Fig. 1(a) point at
24 poses and the noise of Fig. 1(b)-(e) is the same data-generating setting.

:func:`grid_points` merges the experiments into one job per grid point
``(n_poses, noise_std, g_error)``, each with the union of the cases
``(data_model, g_error, methods)`` the experiments need there.  The data of a job come
from the stream of ``(n_poses, noise_std)`` (:mod:`accelcal_repro.montecarlo`): the jobs of one
noise level and pose count at different g errors see the same data (common random
numbers), and splitting them into jobs changes no number.  A method is left out at a
pose count below its minimum q + 1 (10 full, 4 bias-only).
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


def noise_key(x: float) -> str:
    """File-name key of a noise level, e.g. 1e-07, 0.001 (exact: 12 significant digits)."""
    return format(float(x), ".12g")


def point_key(n_poses: int, noise_std: float, g_error: float = 0.0) -> str:
    """Job key of a grid point, e.g. ``n24_s0.0001_g0`` or ``n24_s0.0001_g0.01``."""
    return f"n{int(n_poses)}_s{noise_key(noise_std)}_g{noise_key(g_error)}"


def grid_points(experiments: Mapping[str, Experiment]) -> dict[str, dict]:
    """One entry per grid point ``(n_poses, noise_std, g_error)``, sorted by pose count,
    noise and g error: ``{key: {"n_poses", "noise_std", "g_error", "cases":
    [[data_model, g_error, [methods]], ...]}}`` with the union of what every experiment
    needs there."""
    need: dict[tuple[int, float, float], dict[str, set]] = {}
    for e in experiments.values():
        for n in e.n_poses:
            methods = {m for m in e.methods if n >= min_poses(m)}
            if not methods:
                continue
            for s in e.noise_std:
                for dg in e.g_error:
                    need.setdefault((n, s, dg), {}).setdefault(e.data_model, set()).update(methods)
    out = {}
    for (n, s, dg) in sorted(need):
        cases = [[dm, dg, [m for m in METHODS if m in need[n, s, dg][dm]]]
                 for dm in DATA_MODELS if dm in need[n, s, dg]]
        out[point_key(n, s, dg)] = {"n_poses": n, "noise_std": s, "g_error": dg, "cases": cases}
    return out


def select(table: pd.DataFrame, experiment: Experiment) -> pd.DataFrame:
    """The rows of a summary (or tidy) table that belong to ``experiment``."""
    e = experiment
    sel = (table["data_model"].eq(e.data_model) & table["n_poses"].isin(e.n_poses)
           & table["noise_std"].isin(e.noise_std) & table["g_error"].isin(e.g_error))
    if "method" in table:
        sel &= table["method"].isin(e.methods)
    return table[sel].reset_index(drop=True)


__all__ = ["EXPERIMENTS", "Experiment", "experiments_from_config", "grid_points", "noise_key", "point_key", "select"]
