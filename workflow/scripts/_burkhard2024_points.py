"""The Burkhard (2024) experiments split into Monte Carlo jobs: one job per grid point.

An experiment of the config (one panel of Fig. 1, or an analysis beyond the paper;
:class:`accelcal_repro.burkhard2024.grid.Experiment`) is a product grid: one data set
(``data_model``), pose counts, noise levels, errors in the assumed g and the methods to run.
Experiments share grid points: the Fig. 1(a) point at 24 poses and the noise of Fig. 1(b)-(e)
is the same data-generating setting.  :func:`grid_points` merges them into one job per grid
point ``(n_poses, noise_std, g_error)``, each with the union of the cases ``(data_model,
g_error, methods)`` the experiments need there.  The data of a job come from the stream of
``(n_poses, noise_std)`` (:mod:`accelcal_repro.montecarlo`): the jobs of one noise level and
pose count at different g errors see the same data (common random numbers), and splitting
them into jobs changes no number.  A method is left out at a pose count below its minimum
(10 full, 4 bias-only: the registry's ``min_poses``).

Standard library only, and the pose minima come from the estimator registry's own table
read as plain JSON (``_registry_table.py``): the workflow splits the grid while it is parsed
(every ``snakemake`` call and every SLURM job), and that imports no accelcal module.
"""

from __future__ import annotations

from collections.abc import Mapping

from _registry_table import accelerometer_estimators

_METHODS = accelerometer_estimators()
#: Fewest poses of each method, in the order tables and figures use (accelcal_repro.montecarlo.METHODS).
FEWEST = {m: e["fewest"] for m, e in _METHODS.items()}
#: The data sets of a grid point, in the order of the cases: one per model of the methods
#: (``full``: the drawn M != I, ``bias``: M = I; accelcal_repro.montecarlo.DATA_MODELS).
DATA_MODELS = tuple(dict.fromkeys(e["model"] for e in _METHODS.values()))


def noise_key(x: float) -> str:
    """File-name key of a noise level, e.g. 1e-07, 0.001 (exact: 12 significant digits)."""
    return format(float(x), ".12g")


def point_key(n_poses: int, noise_std: float, g_error: float = 0.0) -> str:
    """Job key of a grid point, e.g. ``n24_s0.0001_g0`` or ``n24_s0.0001_g0.01``."""
    return f"n{int(n_poses)}_s{noise_key(noise_std)}_g{noise_key(g_error)}"


def unusable_methods(experiment: Mapping) -> list[str]:
    """The methods of an experiment (a config mapping) that none of its pose counts allows."""
    return sorted(m for m in experiment["methods"] if not any(int(n) >= FEWEST[m] for n in experiment["n_poses"]))


def grid_points(experiments: Mapping[str, Mapping]) -> dict[str, dict]:
    """One entry per grid point ``(n_poses, noise_std, g_error)`` of the experiments (the
    ``experiments`` mapping of the stage config), sorted by pose count, noise and g error:
    ``{key: {"n_poses", "noise_std", "g_error", "cases": [[data_model, g_error, [methods]], ...]}}``
    with the union of what every experiment needs there."""
    need: dict[tuple[int, float, float], dict[str, set]] = {}
    for e in experiments.values():
        for n in map(int, e["n_poses"]):
            methods = {m for m in e["methods"] if n >= FEWEST[m]}
            if not methods:
                continue
            for s in map(float, e["noise_std"]):
                for dg in map(float, e["g_error"]):
                    need.setdefault((n, s, dg), {}).setdefault(e["data_model"], set()).update(methods)
    out = {}
    for (n, s, dg) in sorted(need):
        cases = [[dm, dg, [m for m in FEWEST if m in need[n, s, dg][dm]]]
                 for dm in DATA_MODELS if dm in need[n, s, dg]]
        out[point_key(n, s, dg)] = {"n_poses": n, "noise_std": s, "g_error": dg, "cases": cases}
    return out
