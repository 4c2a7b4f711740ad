"""Monte Carlo runners of the reproduction, as pure functions (arguments in, DataFrame out).

Randomness
----------
Every grid point (e.g. one noise level) draws its data from its own stream,
``np.random.default_rng(grid_seed(seed, stage, value))``, derived from the master seed
and the *value* of the grid point (not its position in a list).  A grid point's data
therefore do not depend on which other grid points run, in which order, or in how
many chunks (jobs) the grid is split: running ``noise_std=[1e-4]`` alone gives the
rows that ``noise_std=[1e-5, 1e-4]`` gives for 1e-4.

Burkhard setting (:func:`crlb_mc_point`)
----------------------------------------
Per trial: true errors from :func:`accelcal.simulation.sample_truth` (Burkhard Sec. 2
ranges), ``n_poses`` directions uniform on the sphere, one draw of the noise ``e``.
The full methods see ``z = M g u + b + e``, the bias-only methods
``z = g u + b + e`` (same ``u``, ``b`` and ``e``, but ``M = I`` so that the Cramér–Rao
bound of the bias-only model applies).  Every method of a family sees identical data.

Error columns (one row per trial × method): ``bias_err_{x,y,z}`` = estimate - truth
[m/s²], ``bias_err_norm`` its Euclidean norm, ``scale_err`` = ``||ŝ - s||``,
``nonorth_err`` = ``||θ̂ - θ||`` [rad] (NaN for the bias-only methods, which do not
estimate them), ``valid`` and ``status`` (``ok`` / IPOPT status / error class), and the
per-trial bounds ``bias_crlb_rms``, ``scale_crlb_rms``, ``nonorth_crlb_rms``
(``sqrt(trace)`` of the CRLB blocks, :mod:`accelcal.uncertainty`).
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Mapping, Sequence
from functools import partial

import numpy as np
import pandas as pd

from .als import full_als
from .errors import AccelcalError
from .lls import bias_lls_batch, full_lls_batch
from .model import params_from_m
from .nlls import nlls_batch
from .simulation import random_directions, sample_truth, simulate_poses
from .uncertainty import crlb

#: Gravity of the Burkhard simulations (Sec. 2).
G_BURKHARD = 9.8055

#: A batch estimator: ``(z (T, n, 3), g, noise_std) -> dict(bias (T,3), M (T,3,3), valid (T,), status (T,))``.
BatchEstimator = Callable[[np.ndarray, float, float], dict]


def _lls_full(z, g, noise_std):
    r = full_lls_batch(z, g)
    return {"bias": r.bias, "M": r.M, "valid": r.valid,
            "status": np.where(r.valid, "ok", "NotPositiveDefiniteError")}


def _lls_bias(z, g, noise_std):
    r = bias_lls_batch(z, g)
    return {"bias": r.bias, "M": r.M, "valid": r.valid, "status": np.where(r.valid, "ok", "invalid")}


def _nlls(model):
    def run(z, g, noise_std):
        r = nlls_batch(z, g, model)
        return {"bias": r["bias"], "M": r["M"], "valid": r["valid"], "status": r["status"].astype(str)}
    run.__name__ = f"{model}_nlls"
    return run


def als_loop(z, g, noise_std, known_noise: bool = True) -> dict:
    """:func:`accelcal.full_als` over trials; typed failures are recorded, not raised.

    ``known_noise``: pass the simulation's noise std to ALS (the project's default: a
    simulation knows it, and a real calibration measures it at rest) or let ALS
    estimate it from the 24 poses.
    """
    T = len(z)
    out = {"bias": np.full((T, 3), np.nan), "M": np.full((T, 3, 3), np.nan),
           "valid": np.zeros(T, bool), "status": np.empty(T, dtype=object)}
    for i in range(T):
        try:
            r = full_als(z[i], g, noise_std=noise_std if known_noise else None)
        except AccelcalError as e:
            out["status"][i] = type(e).__name__
            continue
        out["bias"][i], out["M"][i], out["valid"][i], out["status"][i] = r.bias, r.M, True, "ok"
    out["status"] = out["status"].astype(str)
    return out


#: The estimators of the foundation Monte Carlo, by method name, and the model each fits.
BATCH_ESTIMATORS: dict[str, BatchEstimator] = {
    "full_lls": _lls_full,
    "full_als": als_loop,
    "full_nlls": _nlls("full"),
    "bias_lls": _lls_bias,
    "bias_nlls": _nlls("bias"),
}
FULL_METHODS = ("full_lls", "full_als", "full_nlls")
BIAS_METHODS = ("bias_lls", "bias_nlls")


def method_model(method: str) -> str:
    """'bias' for a bias-only method (data generated with M = I), else 'full'."""
    return "bias" if method.startswith("bias") else "full"


def grid_seed(seed: int, stage: str, *values: float) -> np.random.SeedSequence:
    """Seed sequence of one grid point: master ``seed``, ``stage`` name and grid values.

    Floats enter by their exact IEEE-754 bits, strings by CRC-32, so the stream of a
    grid point depends only on what the grid point *is*.
    """
    key = [zlib.crc32(stage.encode())]
    for v in values:
        if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
            key.append(int(v))
        else:
            key.append(struct.unpack("<Q", struct.pack("<d", float(v)))[0])
    return np.random.SeedSequence(entropy=int(seed), spawn_key=tuple(key))


def simulate_burkhard_trials(ss: np.random.SeedSequence, trials: int, n_poses: int, g: float,
                             noise_std: float, truth_ranges: Mapping | None = None) -> dict[str, np.ndarray]:
    """Data of one grid point: truths, directions and the two measurement sets.

    Returns ``truth`` (dict of :func:`sample_truth`), ``directions`` (T, n, 3),
    ``z_full`` (data with the true M) and ``z_bias`` (same directions, bias and noise
    draw, but ``M = I``).
    """
    truth_ss, noise_ss = ss.spawn(2)
    rng = np.random.default_rng(truth_ss)
    truth = sample_truth(rng, trials, **dict(truth_ranges or {}))
    u = random_directions(rng, n_poses, trials)
    # the same noise draw e for both data sets: two generators from one seed
    z_full = simulate_poses(u, g, truth["M"], truth["bias"], noise_std, np.random.default_rng(noise_ss))
    z_bias = simulate_poses(u, g, np.eye(3), truth["bias"], noise_std, np.random.default_rng(noise_ss))
    return {"truth": truth, "directions": u, "z_full": z_full, "z_bias": z_bias}


def crlb_per_trial(directions: np.ndarray, g: float, noise_std: float, M: np.ndarray | None,
                   model: str) -> dict[str, np.ndarray]:
    """Per-trial CRLB RMS of the bias, scale-factor and non-orthogonality errors."""
    T = len(directions)
    out = {k: np.full(T, np.nan) for k in ("bias_crlb_rms", "scale_crlb_rms", "nonorth_crlb_rms")}
    for i in range(T):
        b = crlb(directions[i], g, noise_std, None if M is None else M[i], model)
        out["bias_crlb_rms"][i] = b.bias_rms
        out["scale_crlb_rms"][i] = b.scale_rms
        out["nonorth_crlb_rms"][i] = b.nonorth_rms
    return out


def error_columns(est: Mapping, truth: Mapping, model: str) -> dict[str, np.ndarray]:
    """Estimate-minus-truth columns for one method over trials (NaN where invalid)."""
    valid = np.asarray(est["valid"], bool)
    db = np.where(valid[:, None], est["bias"] - truth["bias"], np.nan)
    cols = {"bias_err_x": db[:, 0], "bias_err_y": db[:, 1], "bias_err_z": db[:, 2],
            "bias_err_norm": np.linalg.norm(db, axis=1)}
    T = len(valid)
    ds = np.full(T, np.nan)
    dth = np.full(T, np.nan)
    if model == "full" and valid.any():
        s, th = params_from_m(np.asarray(est["M"])[valid])
        ds[valid] = np.linalg.norm(s - truth["scale_factors"][valid], axis=1)
        dth[valid] = np.linalg.norm(th - truth["nonorthogonality"][valid], axis=1)
    cols["scale_err"], cols["nonorth_err"] = ds, dth
    return cols


def crlb_mc_point(seed: int, noise_std: float, trials: int, n_poses: int = 24, g: float = G_BURKHARD,
                  methods: Sequence[str] = FULL_METHODS + BIAS_METHODS,
                  truth_ranges: Mapping | None = None, als_known_noise: bool = True,
                  estimators: Mapping[str, BatchEstimator] | None = None,
                  stage: str = "foundation_crlb") -> pd.DataFrame:
    """Monte Carlo of the Burkhard setting at one noise level: one row per trial × method.

    Parameters
    ----------
    seed : int
        Master seed; the grid point's stream is :func:`grid_seed` ``(seed, stage, noise_std)``.
    noise_std : float
        Per-axis noise std of the pose means [m/s²].
    trials, n_poses, g
        Monte Carlo size, poses per trial, gravity.
    methods : sequence of str
        Keys of ``estimators`` (default :data:`BATCH_ESTIMATORS`).
    estimators : mapping, optional
        Replace or add batch estimators (tests inject deliberately wrong ones).
    """
    table = dict(BATCH_ESTIMATORS)
    table["full_als"] = partial(als_loop, known_noise=als_known_noise)
    if estimators:
        table.update(estimators)
    unknown = [m for m in methods if m not in table]
    if unknown:
        raise KeyError(f"unknown method(s) {unknown}; known: {sorted(table)}")
    data = simulate_burkhard_trials(grid_seed(seed, stage, noise_std), trials, n_poses, g, noise_std,
                                    truth_ranges)
    truth = data["truth"]
    bounds = {}
    frames = []
    for method in methods:
        model = method_model(method)
        z = data["z_bias"] if model == "bias" else data["z_full"]
        est = table[method](z, g, noise_std)
        if model not in bounds:
            bounds[model] = crlb_per_trial(data["directions"], g, noise_std,
                                           truth["M"] if model == "full" else None, model)
        cols = {"noise_std": np.full(trials, float(noise_std)), "trial": np.arange(trials),
                "method": np.full(trials, method, dtype=object)}
        cols.update(error_columns(est, truth, model))
        cols["valid"] = np.asarray(est["valid"], bool)
        cols["status"] = np.asarray(est["status"], dtype=object)
        cols.update(bounds[model])
        frames.append(pd.DataFrame(cols))
    return pd.concat(frames, ignore_index=True)


def crlb_mc(seed: int, noise_levels: Sequence[float], trials: int, **kwargs) -> pd.DataFrame:
    """:func:`crlb_mc_point` over a list of noise levels (each with its own stream)."""
    return pd.concat([crlb_mc_point(seed, s, trials, **kwargs) for s in noise_levels], ignore_index=True)


def _rms(x: pd.Series) -> float:
    x = x.dropna()
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


def rms_ratio(err: np.ndarray, bound: np.ndarray) -> tuple[float, float]:
    """``R = sqrt(mean(err²) / mean(bound²))`` and its standard error (delta method on the
    ratio of means, so that trial-to-trial changes of the bound are accounted for)."""
    e2, c2 = np.square(np.asarray(err, float)), np.square(np.asarray(bound, float))
    ok = np.isfinite(e2) & np.isfinite(c2)
    e2, c2 = e2[ok], c2[ok]
    n = len(e2)
    if n < 2 or c2.mean() <= 0:
        return float("nan"), float("nan")
    r2 = e2.mean() / c2.mean()
    se_r2 = np.std(e2 - r2 * c2, ddof=1) / np.sqrt(n) / c2.mean()
    r = float(np.sqrt(r2))
    return r, float(se_r2 / (2 * r)) if r > 0 else float("nan")


def summarize_crlb(df: pd.DataFrame) -> pd.DataFrame:
    """Per noise × method: RMS errors over valid trials, the CRLB RMS over the same
    trials (``sqrt`` of the mean per-trial bound, cf. :func:`accelcal.crlb_mean`), their
    ratio with its standard error (:func:`rms_ratio`), the largest bias error and the
    trial counts."""
    rows = []
    for (noise, method), d in df.groupby(["noise_std", "method"], sort=False):
        v = d[d["valid"]]
        row = {"noise_std": noise, "method": method, "model": method_model(method),
               "n_trials": len(d), "n_valid": len(v)}
        for q, err in (("bias", "bias_err_norm"), ("scale", "scale_err"), ("nonorth", "nonorth_err")):
            row[f"{q}_rms"], row[f"{q}_crlb_rms"] = _rms(v[err]), _rms(v[f"{q}_crlb_rms"])
            row[f"{q}_ratio"], row[f"{q}_ratio_se"] = rms_ratio(v[err], v[f"{q}_crlb_rms"])
        row["bias_max"] = float(v["bias_err_norm"].max()) if len(v) else float("nan")
        rows.append(row)
    out = pd.DataFrame(rows)
    return out.sort_values(["noise_std", "method"], kind="stable", ignore_index=True)


__all__ = [
    "BATCH_ESTIMATORS",
    "BIAS_METHODS",
    "FULL_METHODS",
    "G_BURKHARD",
    "als_loop",
    "crlb_mc",
    "crlb_mc_point",
    "crlb_per_trial",
    "error_columns",
    "grid_seed",
    "method_model",
    "rms_ratio",
    "simulate_burkhard_trials",
    "summarize_crlb",
]
