"""Monte Carlo engine of the Burkhard et al. (2024) reproduction, as pure functions
(arguments in, DataFrame out).

Grid point and randomness
-------------------------
A *grid point* is a data-generating setting: pose count ``n_poses`` and noise std
``noise_std``.  It draws its data from its own stream,
``grid_seed(seed, stage, n_poses, noise_std)``, derived from the master seed and the
*values* of the point (not its position in a list), so a point's data do not depend on
which other points run, in which order, or how the grid is split into jobs.

Per trial: true errors from :func:`accelcal.simulation.sample_truth` (Sec. 2 ranges),
``n_poses`` directions ``u`` uniform on the sphere (the paper does not state its pose
distribution) and one noise draw ``e``.  From these, two data sets (``data_model``):

* ``full``: ``z = M g u + b + e`` with the drawn ``M ≠ I`` (the paper's Fig. 1(a)-(d));
* ``bias``: ``z = g u + b + e``, the same ``u``, ``b`` and ``e`` but ``M = I`` (Fig. 1(e),
  and the data for which the bias-only Cramér–Rao bound holds).

Every method then runs on identical data, with the assumed gravity ``g + g_error``
(``g_error``: the error in the assumed g of Fig. 1(c)-(e)).  The g error is a setting of
the estimators, not of the data: all g errors of a point see the same data (common
random numbers), so a method that does not use g gives exactly the same estimate at
every g error.

Table (:func:`mc_point`, one row per trial × case × method)
-----------------------------------------------------------
``n_poses, noise_std, data_model, g_error, trial, method, model, valid, status,
iterations`` (IPOPT's iterations for the NLLS, 0 for the closed forms);
estimate - truth: ``bias_err_{x,y,z}`` [m/s²], ``scale_err_{x,y,z}`` [-],
``nonorth_err_{xy,zx,zy}`` [rad] (NaN for the bias-only methods, which do not estimate
them) and their Euclidean norms ``*_err_norm``; the truth ``true_bias_*``,
``true_scale_*``, ``true_nonorth_*`` (zero scale and non-orthogonality for
``data_model='bias'``); the per-trial Cramér–Rao bounds ``bias_crlb_rms``,
``scale_crlb_rms``, ``nonorth_crlb_rms`` (``sqrt(trace)`` of the blocks) *of the
method's own model on these data*: NaN where the model is misspecified (a bias-only
method on ``full`` data), and the bound of a known g (it does not depend on ``g_error``).
"""

from __future__ import annotations

import struct
import time
import zlib
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from accelcal.model import dM_dparams, params_from_m
from accelcal.registry import ESTIMATORS, estimator, estimators
from accelcal.simulation import random_directions, sample_truth, simulate_poses

#: Gravity of the Burkhard simulations (Sec. 2).
G_BURKHARD = 9.8055

#: A batch estimator: ``(z (T, n, 3), g, noise_std) -> dict(bias (T,3), M (T,3,3), valid (T,), status (T,)[,
#: iterations (T,)])``.
BatchEstimator = Callable[[np.ndarray, float, float], dict]

#: Every method, in the order tables and figures use (the registry's accelerometer estimators).
METHODS = tuple(e.name for e in estimators("accelerometer"))
FULL_METHODS = tuple(m for m in METHODS if ESTIMATORS[m].model == "full")
BIAS_METHODS = tuple(m for m in METHODS if ESTIMATORS[m].model == "bias")
#: The data sets of a grid point (see the module docstring), one per model of the methods:
#: ``full`` (the drawn M != I), ``bias`` (M = I).  The workflow derives the same tuple from
#: the registry's table (workflow/scripts/_burkhard2024_points.py).
DATA_MODELS = tuple(dict.fromkeys(ESTIMATORS[m].model for m in METHODS))
#: Axis labels of the error columns.
AXES = {"bias": ("x", "y", "z"), "scale": ("x", "y", "z"), "nonorth": ("xy", "zx", "zy")}
QUANTITIES = tuple(AXES)


def batch_estimator(method: str, known_noise: Mapping[str, bool] | None = None) -> BatchEstimator:
    """The registry's batched form of ``method`` (:meth:`accelcal.registry.Estimator.fit_batch`)
    as a Monte Carlo estimator; typed failures are recorded in ``status``, not raised.

    ``known_noise``: per use of the noise level (:data:`accelcal.registry.NOISE_USES`:
    ALS's ``correction``, NLLS's ``stopping``), whether the estimator is told the
    simulation's noise std (default: yes; a simulation knows it, and a real calibration
    measures it at rest) or works without it (ALS estimates it from the poses, NLLS
    stops at IPOPT's default tolerance).
    """
    e = estimator(method)
    told = e.needs_noise and (known_noise or {}).get(e.noise_use, True)

    def run(z, g, noise_std):
        r = e.fit_batch(z, g, noise_std=noise_std if told else None)
        out = {"bias": r.bias, "M": r.M, "valid": r.valid, "status": r.status}
        if r.iterations is not None:
            out["iterations"] = r.iterations
        return out

    run.__name__ = f"{method}_batch"
    return run


def method_model(method: str) -> str:
    """'bias' for a bias-only method (it assumes M = I), else 'full' (:mod:`accelcal.registry`)."""
    return estimator(method).model


def min_poses(method: str) -> int:
    """Fewest poses a method accepts: q + 1 for q unknowns (10 full, 4 bias-only; paper Sec. 1.2)."""
    return estimator(method).min_poses


def grid_seed(seed: int, stage: str, *values: float) -> np.random.SeedSequence:
    """Seed sequence of one grid point: master ``seed``, ``stage`` name and grid values.

    Integers enter as themselves, floats by their exact IEEE-754 bits, the stage by its
    CRC-32, so the stream of a grid point depends only on what the grid point *is*.
    """
    key = [zlib.crc32(stage.encode())]
    for v in values:
        if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
            key.append(int(v))
        else:
            key.append(struct.unpack("<Q", struct.pack("<d", float(v)))[0])
    return np.random.SeedSequence(entropy=int(seed), spawn_key=tuple(key))


def simulate_trials(ss: np.random.SeedSequence, trials: int, n_poses: int, g: float, noise_std: float,
                    truth_ranges: Mapping | None = None) -> dict:
    """Data of one grid point: ``truth`` (dict of :func:`sample_truth`), ``directions``
    (T, n, 3) and ``z`` = {``'full'``: data with the drawn M, ``'bias'``: the same
    directions, bias and noise draw with M = I}."""
    truth_ss, noise_ss = ss.spawn(2)
    rng = np.random.default_rng(truth_ss)
    truth = sample_truth(rng, trials, **dict(truth_ranges or {}))
    u = random_directions(rng, n_poses, trials)
    # the same noise draw e for both data sets: two generators from one seed
    z = {"full": simulate_poses(u, g, truth["M"], truth["bias"], noise_std, np.random.default_rng(noise_ss)),
         "bias": simulate_poses(u, g, np.eye(3), truth["bias"], noise_std, np.random.default_rng(noise_ss))}
    return {"truth": truth, "directions": u, "z": z}


def _tangents(u: np.ndarray) -> np.ndarray:
    """Two orthonormal tangent vectors of the sphere at each ``u`` (..., 3) -> (..., 3, 2)."""
    helper = np.where(np.abs(u[..., :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    t1 = np.cross(u, helper)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    return np.stack([t1, np.cross(u, t1)], axis=-1)


def crlb_batch(directions: np.ndarray, g: float, noise_std, M: np.ndarray | None = None,
               model: str = "full") -> np.ndarray:
    """Cramér–Rao covariance of every trial at once, ``(T, q, q)``.

    The same bound as :func:`accelcal.uncertainty.crlb` (unknown pose directions
    eliminated by the Schur complement, g known), vectorised over trials: the per-trial
    call costs about 1 ms, which would rival the NLLS in the Monte Carlo.  A test
    checks both against each other.
    """
    u = np.asarray(directions, float)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    T, n, _ = u.shape
    Ms = np.broadcast_to(np.eye(3), (T, 3, 3)) if (M is None or model == "bias") else np.asarray(M, float)
    Sinv = np.diag(1.0 / np.broadcast_to(np.asarray(noise_std, float) ** 2, (3,)))
    q = 3 if model == "bias" else 9
    J = np.zeros((T, n, 3, q))
    J[..., :3] = np.eye(3)
    if model == "full":
        s, th = params_from_m(Ms)
        dM = np.stack([dM_dparams(s[i], th[i]) for i in range(T)])  # (T, 6, 3, 3)
        J[..., 3:] = g * np.einsum("tkij,tnj->tnik", dM, u)
    tan = g * (Ms[:, None] @ _tangents(u))  # (T, n, 3, 2)
    STi = Sinv @ tan
    info = np.swapaxes(tan, -1, -2) @ STi  # (T, n, 2, 2)
    W = Sinv - STi @ np.linalg.inv(info) @ np.swapaxes(STi, -1, -2)
    F = np.einsum("tnji,tnjl->til", J, W @ J)
    return np.linalg.inv(F)


def crlb_per_trial(directions: np.ndarray, g: float, noise_std: float, M: np.ndarray | None,
                   model: str) -> dict[str, np.ndarray]:
    """Per-trial CRLB RMS (``sqrt(trace)`` of each block) of the bias, scale-factor and
    non-orthogonality errors (NaN for the latter two in the bias-only model)."""
    cov = crlb_batch(directions, g, noise_std, M, model)
    T = len(cov)

    def block(k):
        return np.sqrt(np.trace(cov[:, k:k + 3, k:k + 3], axis1=1, axis2=2)) if cov.shape[1] > k else np.full(T, np.nan)

    return {"bias_crlb_rms": block(0), "scale_crlb_rms": block(3), "nonorth_crlb_rms": block(6)}


def truth_columns(truth: Mapping, data_model: str) -> dict[str, np.ndarray]:
    """The true errors of every trial (zero scale and non-orthogonality for M = I data)."""
    s, th = truth["scale_factors"], truth["nonorthogonality"]
    if data_model == "bias":
        s, th = np.zeros_like(s), np.zeros_like(th)
    cols = {}
    for q, v in (("bias", truth["bias"]), ("scale", s), ("nonorth", th)):
        for k, ax in enumerate(AXES[q]):
            cols[f"true_{q}_{ax}"] = v[:, k]
    return cols


def error_columns(est: Mapping, truth: Mapping, model: str, data_model: str = "full") -> dict[str, np.ndarray]:
    """Estimate-minus-truth columns of one method over trials (NaN where invalid, and
    for scale and non-orthogonality of a bias-only method)."""
    valid = np.asarray(est["valid"], bool)
    T = len(valid)
    errs = {"bias": np.where(valid[:, None], np.asarray(est["bias"], float) - truth["bias"], np.nan),
            "scale": np.full((T, 3), np.nan), "nonorth": np.full((T, 3), np.nan)}
    if model == "full" and valid.any():
        t = truth_columns(truth, data_model)
        s, th = params_from_m(np.asarray(est["M"], float)[valid])
        errs["scale"][valid] = s - np.column_stack([t[f"true_scale_{a}"] for a in AXES["scale"]])[valid]
        errs["nonorth"][valid] = th - np.column_stack([t[f"true_nonorth_{a}"] for a in AXES["nonorth"]])[valid]
    cols = {}
    for q, e in errs.items():
        for k, ax in enumerate(AXES[q]):
            cols[f"{q}_err_{ax}"] = e[:, k]
        cols[f"{q}_err_norm"] = np.linalg.norm(e, axis=1)
    return cols


def normalise_cases(cases: Iterable) -> list[tuple[str, float, tuple[str, ...]]]:
    """``[(data_model, g_error, methods), ...]`` with checked names, methods in :data:`METHODS` order."""
    out = []
    for data_model, g_error, methods in cases:
        if data_model not in DATA_MODELS:
            raise ValueError(f"data_model must be one of {DATA_MODELS}, not {data_model!r}")
        out.append((data_model, float(g_error), tuple(methods)))
    return out


def mc_point(seed: int, n_poses: int, noise_std: float, cases: Iterable, trials: int, g: float = G_BURKHARD,
             truth_ranges: Mapping | None = None, als_known_noise: bool = True, nlls_known_noise: bool = True,
             estimators: Mapping[str, BatchEstimator] | None = None,
             stage: str = "burkhard2024") -> tuple[pd.DataFrame, pd.DataFrame]:
    """Monte Carlo of one grid point: every case on the point's data.

    Parameters
    ----------
    seed : int
        Master seed; the point's stream is :func:`grid_seed` ``(seed, stage, n_poses, noise_std)``.
    n_poses, noise_std : int, float
        The grid point: poses per trial and per-axis noise std of the pose means [m/s²].
    cases : iterable of (data_model, g_error, methods)
        Which methods run on which data set (``'full'`` or ``'bias'``) with which error
        in the assumed g [m/s²] (assumed g = ``g + g_error``).
    trials : int
        Monte Carlo runs.
    als_known_noise, nlls_known_noise : bool
        Tell the estimators that use the noise level for a correction (ALS) and those
        that use it for their stopping rule (NLLS, :func:`accelcal.nlls.solver_tol`) the
        noise std of the simulation (:func:`batch_estimator`).
    estimators : mapping, optional
        Replace or add batch estimators (tests inject deliberately wrong ones); the
        others are the registry's (:func:`batch_estimator`).

    Returns
    -------
    table : DataFrame
        One row per trial × case × method (columns in the module docstring).
    timing : DataFrame
        ``n_poses, noise_std, data_model, g_error, method, trials, seconds``: wall time of
        each method over all trials of a case (its batched form), measured while the
        Monte Carlo runs.
    """
    cases = normalise_cases(cases)
    table = _batch_estimators(cases, {"correction": als_known_noise, "stopping": nlls_known_noise}, estimators)
    data = simulate_trials(grid_seed(seed, stage, int(n_poses), float(noise_std)), trials, int(n_poses), g,
                           noise_std, truth_ranges)
    bound = _Bounds(data, g, noise_std, trials)
    frames, timings = [], []
    for data_model, g_error, methods in cases:
        z = data["z"][data_model]
        g_assumed = g + g_error
        for method in methods:
            table[method](z[:1], g_assumed, noise_std)  # untimed warm-up: kernels loaded, solver built
            t0 = time.perf_counter()
            est = table[method](z, g_assumed, noise_std)
            timings.append((int(n_poses), float(noise_std), data_model, g_error, method, trials,
                            time.perf_counter() - t0))
            frames.append(_method_rows(est, data["truth"], bound, trials, int(n_poses), float(noise_std),
                                       data_model, g_error, method))
    timing = pd.DataFrame(timings, columns=["n_poses", "noise_std", "data_model", "g_error", "method", "trials",
                                            "seconds"])
    return pd.concat(frames, ignore_index=True), timing


def _batch_estimators(cases, told: dict, estimators: Mapping | None) -> dict:
    """``{method: batch estimator}`` of every method the cases run (the registry's, told the
    noise level as ``told`` says, then ``estimators``); unknown methods raise KeyError."""
    wanted = {m for _, _, ms in cases for m in ms}
    table = {m: batch_estimator(m, told) for m in wanted if m in ESTIMATORS}
    table.update(estimators or {})
    unknown = sorted(wanted - set(table))
    if unknown:
        raise KeyError(f"unknown method(s) {unknown}; known: {sorted(set(ESTIMATORS) | set(table))}")
    return table


class _Bounds:
    """The per-trial Cramér-Rao bounds of each (data set, model), computed once each."""

    def __init__(self, data: dict, g: float, noise_std: float, trials: int):
        self.data, self.g, self.noise_std, self.trials, self.bounds = data, g, noise_std, trials, {}

    def __call__(self, data_model: str, model: str) -> dict:
        if model == "bias" and data_model == "full":  # misspecified: no bound for this model
            return {k: np.full(self.trials, np.nan) for k in ("bias_crlb_rms", "scale_crlb_rms", "nonorth_crlb_rms")}
        if (data_model, model) not in self.bounds:
            M = self.data["truth"]["M"] if data_model == "full" else None
            self.bounds[data_model, model] = crlb_per_trial(self.data["directions"], self.g, self.noise_std, M, model)
        return self.bounds[data_model, model]


def _method_rows(est: dict, truth: dict, bound: _Bounds, trials: int, n_poses: int, noise_std: float,
                 data_model: str, g_error: float, method: str) -> pd.DataFrame:
    """The table's rows of one method on one case: one per trial (columns in the module docstring)."""
    model = method_model(method)
    cols = {"n_poses": np.full(trials, n_poses), "noise_std": np.full(trials, noise_std),
            "data_model": np.full(trials, data_model, dtype=object), "g_error": np.full(trials, g_error),
            "trial": np.arange(trials), "method": np.full(trials, method, dtype=object),
            "model": np.full(trials, model, dtype=object),
            "valid": np.asarray(est["valid"], bool), "status": np.asarray(est["status"], dtype=object),
            "iterations": np.asarray(est.get("iterations", np.zeros(trials, int)), int)}
    cols.update(error_columns(est, truth, model, data_model))
    cols.update(truth_columns(truth, data_model))
    cols.update(bound(data_model, model))
    return pd.DataFrame(cols)


def mc_grid(seed: int, points: Iterable[tuple[int, float]], cases: Iterable, trials: int,
            **kwargs) -> pd.DataFrame:
    """:func:`mc_point` over ``(n_poses, noise_std)`` points with the same cases (tables only)."""
    cases = normalise_cases(cases)
    return pd.concat([mc_point(seed, n, s, cases, trials, **kwargs)[0] for n, s in points], ignore_index=True)


# --------------------------------------------------------------------------- summaries
#: Columns that identify one case of one grid point.
CASE_KEYS = ["data_model", "n_poses", "noise_std", "g_error"]


def _rms(x) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


def rms_and_se(x) -> tuple[float, float]:
    """RMS of the finite values and its standard error (delta method: se(mean x²) / (2 RMS))."""
    x = np.asarray(x, float)
    x2 = np.square(x[np.isfinite(x)])
    if len(x2) < 2:
        return (float(np.sqrt(x2.mean())) if len(x2) else float("nan")), float("nan")
    r = float(np.sqrt(x2.mean()))
    return r, float(np.std(x2, ddof=1) / np.sqrt(len(x2)) / (2 * r)) if r > 0 else float("nan")


def rms_ratio(err: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """``R = sqrt(mean(err²) / mean(ref²))`` over the pairs where both are finite, and its
    standard error (delta method on the ratio of means of paired squares).

    ``ref`` is a per-trial bound (RMS / CRLB) or another method's errors on the same
    trials (a paired comparison: the shared part of the two errors cancels in the
    standard error, which is why methods on identical data can be told apart).
    """
    e2, c2 = np.square(np.asarray(err, float)), np.square(np.asarray(ref, float))
    ok = np.isfinite(e2) & np.isfinite(c2)
    e2, c2 = e2[ok], c2[ok]
    n = len(e2)
    if n < 2 or c2.mean() <= 0:
        return float("nan"), float("nan")
    r2 = e2.mean() / c2.mean()
    se_r2 = np.std(e2 - r2 * c2, ddof=1) / np.sqrt(n) / c2.mean()
    r = float(np.sqrt(r2))
    return r, float(se_r2 / (2 * r)) if r > 0 else float("nan")



def relative_norm(d: pd.DataFrame, q: str) -> np.ndarray:
    """``||estimate - truth|| / ||truth||`` per trial (NaN where the truth is 0)."""
    err = d[f"{q}_err_norm"].to_numpy(float)
    true = np.linalg.norm(d[[f"true_{q}_{a}" for a in AXES[q]]].to_numpy(float), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(true > 0, err / true, np.nan)


def summarize(df: pd.DataFrame) -> pd.DataFrame:
    """Per case × method: trial counts, RMS errors over the valid trials with standard
    errors, the CRLB RMS over the same trials (``sqrt`` of the mean per-trial bound),
    RMS / CRLB with its standard error (:func:`rms_ratio`), the RMS of the relative
    errors ``||ŝ - s|| / ||s||`` and ``||θ̂ - θ|| / ||θ||`` (``*_rel_rms``, NaN for M = I
    data), the largest bias error and the mean and largest iteration count
    (``iterations_mean``, ``iterations_max``: IPOPT's for the NLLS, 0 for closed forms)."""
    rows = []
    for key, d in df.groupby(CASE_KEYS + ["method"], sort=False):
        v = d[d["valid"].astype(bool)]
        row = dict(zip(CASE_KEYS + ["method"], key))
        row.update({"model": method_model(row["method"]), "n_trials": len(d), "n_valid": len(v)})
        for q in QUANTITIES:
            row[f"{q}_rms"], row[f"{q}_rms_se"] = rms_and_se(v[f"{q}_err_norm"])
            row[f"{q}_crlb_rms"] = _rms(v[f"{q}_crlb_rms"])
            row[f"{q}_ratio"], row[f"{q}_ratio_se"] = rms_ratio(v[f"{q}_err_norm"], v[f"{q}_crlb_rms"])
        for q in ("scale", "nonorth"):
            row[f"{q}_rel_rms"], row[f"{q}_rel_rms_se"] = rms_and_se(relative_norm(v, q))
        row["bias_max"] = float(v["bias_err_norm"].max()) if len(v) else float("nan")
        if "iterations" in d:  # iterative methods: IPOPT iterations over all trials (0 for closed forms)
            it = d["iterations"].to_numpy(float)
            row["iterations_mean"], row["iterations_max"] = float(it.mean()), float(it.max())
        rows.append(row)
    out = pd.DataFrame(rows)
    order = {m: i for i, m in enumerate(METHODS)}
    out["_m"] = out["method"].map(order).fillna(len(order))
    out = out.sort_values(CASE_KEYS + ["_m", "method"], kind="stable", ignore_index=True)
    return out.drop(columns="_m")


#: Method pairs compared trial by trial (method, reference): ratio = RMS(method) / RMS(reference);
#: every estimator against its baseline, and the estimator a method corrects against it (registry).
PAIRS = tuple((m, ESTIMATORS[m].baseline) for m in METHODS if ESTIMATORS[m].baseline) + \
    tuple((ESTIMATORS[m].corrects, m) for m in METHODS if ESTIMATORS[m].corrects)


def compare_methods(df: pd.DataFrame, pairs: Sequence[tuple[str, str]] = PAIRS) -> pd.DataFrame:
    """Paired comparison of methods on identical data: per case and pair, the RMS ratio
    ``RMS(method) / RMS(reference)`` of each quantity over the trials valid for both, and
    its standard error (:func:`rms_ratio` on the per-trial errors)."""
    rows = []
    for key, d in df.groupby(CASE_KEYS, sort=False):
        by = {m: g.set_index("trial") for m, g in d.groupby("method", sort=False)}
        for method, ref in pairs:
            if method not in by or ref not in by:
                continue
            a, b = by[method], by[ref]
            both = a.index[a["valid"].astype(bool)].intersection(b.index[b["valid"].astype(bool)])
            row = dict(zip(CASE_KEYS, key))
            row.update({"method": method, "reference": ref, "n_pairs": len(both)})
            for q in QUANTITIES:
                row[f"{q}_ratio"], row[f"{q}_ratio_se"] = rms_ratio(a.loc[both, f"{q}_err_norm"],
                                                                    b.loc[both, f"{q}_err_norm"])
            rows.append(row)
    out = pd.DataFrame(rows)
    if len(out):
        out = out.sort_values(CASE_KEYS + ["method", "reference"], kind="stable", ignore_index=True)
    return out


def summarize_mc_timing(timing: pd.DataFrame) -> pd.DataFrame:
    """Wall time per Monte Carlo trial of each method, per pose count: the median over
    the cases (noise levels, data sets, g errors) of ``seconds / trials``."""
    t = timing.assign(per_trial_s=timing["seconds"] / timing["trials"])
    out = (t.groupby(["n_poses", "method"], sort=True)
           .agg(n_cases=("per_trial_s", "size"), per_trial_s=("per_trial_s", "median"),
                total_s=("seconds", "sum"))
           .reset_index())
    return out


__all__ = [
    "AXES",
    "BIAS_METHODS",
    "CASE_KEYS",
    "DATA_MODELS",
    "FULL_METHODS",
    "G_BURKHARD",
    "METHODS",
    "PAIRS",
    "QUANTITIES",
    "batch_estimator",
    "compare_methods",
    "crlb_batch",
    "crlb_per_trial",
    "error_columns",
    "grid_seed",
    "mc_grid",
    "mc_point",
    "method_model",
    "min_poses",
    "normalise_cases",
    "relative_norm",
    "rms_and_se",
    "rms_ratio",
    "simulate_trials",
    "summarize",
    "summarize_mc_timing",
    "truth_columns",
]
