"""Side by side on the same simulated tractor runs: Tereshkov's estimator and the Batista
et al. (2011) Kalman filter (:func:`accelcal.batista.filter.kalman_filter`).

Both see the same IMU samples (same biases, same noise).  Each gets the aiding it needs,
from the same truth:

* Tereshkov: the GNSS-derived external specific force and course (as in
  :mod:`accelcal_repro.tereshkov.vehicle`);
* Batista: the velocity in the sensor frame, ``v_s = C_bsᵀ C_nbᵀ v_n`` plus white noise
  (``velocity_noise_mps``; e.g. odometry with the non-holonomic constraints of a land
  vehicle), as its eq. (7) measurement.

The Batista model has no gyro bias (``ġ = -S(ω) g`` with the measured ω).  It is run
twice: on the raw gyro (``batista``: the same data as Tereshkov) and on the gyro with
its true bias removed (``batista_ideal_gyro``: the paper's calibrated-gyro assumption).
Its tuning is the paper's (Ξ, Θ) with the initial covariance of the project's Batista
config (``P0_std``); initial estimate as in the paper (v̂ = first velocity reading,
ĝ = -a_m, b̂ = 0).

Compute cost: wall time per filter step for one run (Tereshkov: the plain-Python
:func:`~accelcal.tereshkov.estimator.run_estimator_scalar`; Batista: its numpy filter),
and per run-step when runs are batched (Tereshkov: the numpy loop over all runs; the
Batista filter keeps its own covariance per run, so its batched cost is its single-run cost).
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from accelcal.batista.filter import PAPER_THETA, PAPER_XI, kalman_filter
from accelcal.tereshkov.errors import InvalidParameterError
from accelcal.tereshkov.estimator import run_estimator, run_estimator_scalar

from .montecarlo import AXES, ScenarioBatch, build_scenario, convergence_summary, estimator_params
from .vehicle import DEG, sensor_chunks, vehicle_state

METHODS = ("tereshkov", "batista", "batista_ideal_gyro")


def comparison_config(cfg: dict) -> dict:
    """The stage config with the ``comparison`` overrides applied to a field scenario."""
    c = cfg.get("comparison", {})
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in cfg.items()}
    out.setdefault("scenarios", {})
    out["scenarios"] = dict(out["scenarios"]) | {
        "comparison": {"runs": int(c.get("runs", 4)), "duration_s": float(c.get("duration_s", 900)), "path": "field"}}
    if "imu_rate_hz" in c:
        out["imu"] = dict(out.get("imu", {})) | {"rate_hz": float(c["imu_rate_hz"])}
    return out


def _collect(sb: ScenarioBatch, rng_seed: int, velocity_noise: float):
    b = sb.batch
    parts = {k: [] for k in ("t", "gyro", "accel", "f_ext", "course", "speed")}
    for ch in sensor_chunks(b, 60.0):
        for k in parts:
            parts[k].append(getattr(ch, k))
    data = {k: np.concatenate(v, axis=0 if k == "t" else 1) for k, v in parts.items()}
    dt = 1.0 / b.sensors.imu_rate
    st = vehicle_state(b.path, data["t"] + dt / 2, b.sensors.g)
    v_b = np.einsum("rnji,rnj->rni", st.C_nb, st.v_n)
    v_s = np.einsum("rji,rnj->rni", b.C_bs, v_b)
    rng = np.random.default_rng(rng_seed)
    data["velocity"] = v_s + velocity_noise * rng.standard_normal(v_s.shape)
    return data


def run_comparison(cfg: dict, batista_cfg: dict | None = None, record_every_s: float = 1.0):
    """Run the three methods on the comparison runs.

    Parameters
    ----------
    cfg : dict
        The ``tereshkov`` config (its ``comparison`` section: ``runs``, ``duration_s``,
        optionally ``imu_rate_hz``, ``velocity_noise_mps``).
    batista_cfg : dict, optional
        Batista filter settings: ``xi``, ``theta``, ``P0_std`` (default: the paper's Ξ, Θ
        and P0_std = (0.01, 0.2, 0.2)).

    Returns
    -------
    (table, cost) : tidy table (``scenario`` = method, run, t, sensor, axis, estimate,
        truth, error, update_time) and one row per method with the compute cost.
    """

    c = cfg.get("comparison", {})
    bcfg = batista_cfg or {}
    xi = tuple(bcfg.get("xi", PAPER_XI))
    theta = float(bcfg.get("theta", PAPER_THETA))
    p0 = np.asarray(bcfg.get("P0_std", (0.01, 0.2, 0.2)), dtype=float)
    P0 = np.repeat(p0**2, 3)
    ccfg = comparison_config(cfg)
    sb = build_scenario(ccfg, "comparison")
    b = sb.batch
    if b.n_runs < 1:
        raise InvalidParameterError("the comparison needs at least one run")
    data = _collect(sb, int(cfg.get("seed", 0)) + 77, float(c.get("velocity_noise_mps", 0.02)))
    dt = 1.0 / b.sensors.imu_rate
    n = data["gyro"].shape[1]
    rec = max(1, int(round(record_every_s / dt)))
    params = estimator_params(ccfg)
    frames, cost = [], []

    _tereshkov_rows(data, b, dt, n, rec, params, frames, cost)
    for method in ("batista", "batista_ideal_gyro"):  # one Kalman filter per run
        _batista_rows(method, data, b, n, rec, P0, xi, theta, frames, cost)
    table = pd.concat(frames, ignore_index=True)
    return table, pd.DataFrame(cost)


def _tereshkov_rows(data, b, dt, n, rec, params, frames, cost):
    """Tereshkov, batched over runs, then one run alone for the per-run cost (appends to ``frames``, ``cost``)."""
    t0 = time.perf_counter()
    res, _ = run_estimator(data["gyro"], data["accel"], data["f_ext"], data["course"], data["speed"], dt, params,
                           record_every=rec)
    batched_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    one = run_estimator_scalar(data["gyro"][0], data["accel"][0], data["f_ext"][0], data["course"][0],
                               data["speed"][0], dt, params, record_every=rec)
    single_s = time.perf_counter() - t0
    if not np.allclose(one.accel_bias[0], res.accel_bias[0], atol=1e-9):  # two implementations, same numbers
        raise RuntimeError("scalar and vectorised Tereshkov estimators disagree")
    cost.append({"method": "tereshkov", "us_per_step_single_run": 1e6 * single_s / n,
                 "us_per_run_step_batched": 1e6 * batched_s / (n * b.n_runs), "steps": n, "runs": b.n_runs,
                 "states": 9 + 6, "covariance": False})
    for sensor, est, truth, upd, scale in (("gyro", res.gyro_bias, b.gyro_bias, res.gyro_time, 1 / DEG),
                                           ("accel", res.accel_bias, b.accel_bias, res.accel_time, 1.0)):
        for a, ax in enumerate(AXES):
            frames.append(_frame("tereshkov", res.t, est[:, :, a] * scale, truth[:, a] * scale, sensor, ax, upd))


def _batista_rows(method, data, b, n, rec, P0, xi, theta, frames, cost):
    """Batista's filter (``batista_ideal_gyro``: on bias-free gyro data), one per run (appends to
    ``frames``, ``cost``)."""
    gyro = data["gyro"] - (b.gyro_bias[:, None, :] if method == "batista_ideal_gyro" else 0.0)
    est, per_run = [], []
    for r in range(b.n_runs):
        x0 = np.concatenate([data["velocity"][r, 0], -data["accel"][r, 0], np.zeros(3)])
        t0 = time.perf_counter()
        fr = kalman_filter(data["t"], data["accel"][r], gyro[r], data["velocity"][r], x0, P0, xi, theta, rec)
        per_run.append(time.perf_counter() - t0)
        est.append(fr.bias)
    est = np.stack(est)
    cost.append({"method": method, "us_per_step_single_run": 1e6 * float(np.median(per_run)) / n,
                 "us_per_run_step_batched": 1e6 * float(np.sum(per_run)) / (n * b.n_runs), "steps": n,
                 "runs": b.n_runs, "states": 9, "covariance": True})
    t_rec = fr.t
    elapsed = np.broadcast_to(t_rec, est.shape[:2])
    for a, ax in enumerate(("x", "y", "z")):
        frames.append(_frame(method, t_rec, est[:, :, a], b.accel_bias[:, a], "accel", ax, elapsed))


def _frame(method, t, est, truth, sensor, axis, upd):
    R, m = est.shape
    tr = np.repeat(np.asarray(truth)[:, None], m, axis=1)
    return pd.DataFrame({"scenario": method, "run": np.repeat(np.arange(R), m), "t": np.tile(t[:m], R),
                         "sensor": sensor, "axis": axis, "estimate": est.ravel(), "truth": tr.ravel(),
                         "error": (est - tr).ravel(), "update_time": np.asarray(upd)[:, :m].ravel()})


def comparison_summary(table: pd.DataFrame, cost: pd.DataFrame, steady_state_from_s: float,
                       fraction: float = 0.05, nonconvergence_ratio: float = 0.5) -> pd.DataFrame:
    """Per method × sensor (x, y axes; Batista's z accelerometer separately as ``accel_z``):
    convergence time, steady-state RMS and mean |error|, and the compute cost."""

    xy = table[table["axis"].isin(AXES)]
    s = convergence_summary(xy, steady_state_from_s, fraction, nonconvergence_ratio)
    z = table[table["axis"] == "z"].assign(sensor="accel_z")
    if len(z):
        s = pd.concat([s, convergence_summary(z, steady_state_from_s, fraction, nonconvergence_ratio)],
                      ignore_index=True)
    s = s.rename(columns={"scenario": "method"})
    return s.merge(cost.drop(columns=["runs"], errors="ignore"), on="method", how="left")


__all__ = ["METHODS", "comparison_config", "comparison_summary", "run_comparison"]
