"""Monte Carlo runs of the Tereshkov estimator on simulated tractor paths: tidy tables.

Every function takes the ``tereshkov`` config mapping (section ``tereshkov`` of ``config/config.yaml``)
and returns pandas DataFrames.  Runs are vectorised (one estimator loop for all runs
of a scenario); each run draws its truth and noise from its own seed, so results do
not depend on how runs are batched.

Tables
------
* :func:`run_scenario` → one row per run × recorded time × sensor (gyro, accel) ×
  axis (x, y): ``estimate``, ``truth``, ``error`` (gyro in °/s, accelerometer in m/s²),
  ``update_time`` (seconds the estimate has been updating so far) and the scenario's
  group columns (``kind``, ``angle_deg`` in the installation sweep; ``variant`` in the
  artificial-bias test).
* :func:`error_curves` → Monte Carlo mean |error| per time.
* :func:`convergence_summary` → convergence time, steady-state RMS... per group.

Definitions (used by the claims)
--------------------------------
* ``E(t)``: Monte Carlo mean over runs and the x, y axes of ``|b̂(t) - b|``.
* Steady-state error ``E_ss``: mean of ``E`` over ``t ≥ steady_state_from_s``; steady-state
  RMS: root mean square of ``b̂ - b`` over runs, x and y, and ``t ≥ steady_state_from_s``.
* Convergence time: the first time after which ``E(t) - E_ss ≤ f (E(0) - E_ss)`` at every
  later sample, ``f = convergence_fraction`` (0.05: the 95 % settling time, "three time
  constants" of a first-order filter).  Undefined (NaN) when the estimate does not
  converge, i.e. ``E_ss > nonconvergence_ratio · E(0)``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from accelcal.tereshkov.errors import InvalidParameterError
from accelcal.tereshkov.estimator import (TereshkovParams, TereshkovResult, concat_results, run_estimator,
                                          steady_state_torque)

from .vehicle import (DEG, G, Path, SensorSpec, VehicleBatch, field_path, installation_dcm, sensor_chunks, stack_paths,
                      straight_path, vehicle_state)

SENSORS = ("gyro", "accel")
AXES = ("x", "y")


# ----------------------------------------------------------------------------- config


def estimator_params(cfg: dict) -> TereshkovParams:
    """:class:`TereshkovParams` from the ``estimator`` section of the config."""
    e = cfg.get("estimator", {})
    return TereshkovParams(
        tau=e.get("tau_s", 4.0), gyro_filter_s=e.get("gyro_filter_s", 40.0),
        accel_filter_s=e.get("accel_filter_s", 40.0), g=cfg.get("g", G),
        heading_tau=e.get("heading_tau_s", 4.0), straight_rate_dps=e.get("straight_rate_dps", 1.0),
        turn_rate_dps=e.get("turn_rate_dps", 3.0), rate_filter_s=e.get("rate_filter_s", 1.0),
        straight_settle_s=e.get("straight_settle_s", 12.0), turn_settle_s=e.get("turn_settle_s", 8.0),
        min_speed=e.get("min_speed_mps", 1.0), accel_feedback=e.get("accel_feedback", True),
        accel_formula=e.get("accel_formula", "eq14"), estimate_gyro_z=e.get("estimate_gyro_z", True),
    )


def sensor_spec(cfg: dict) -> SensorSpec:
    """:class:`SensorSpec` from the ``imu`` and ``gnss`` sections."""
    imu, gnss = cfg.get("imu", {}), cfg.get("gnss", {})
    g = cfg.get("g", G)
    return SensorSpec(
        imu_rate=imu.get("rate_hz", 50.0), gnss_rate=gnss.get("rate_hz", 10.0),
        gyro_noise=imu.get("gyro_noise_dps_rthz", 0.02) * DEG,
        accel_noise=imu.get("accel_noise_ug_rthz", 150.0) * 1e-6 * g,
        gnss_sigma_h=gnss.get("vel_noise_h_mps", 0.01), gnss_sigma_v=gnss.get("vel_noise_v_mps", 0.02), g=g,
    )


def _signed_uniform(rng, lo_hi, shape):
    lo, hi = lo_hi
    return rng.uniform(lo, hi, shape) * rng.choice((-1.0, 1.0), shape)


def _paths(cfg, kind, seeds, duration):
    v = cfg.get("vehicle", {})
    runs = []
    for s in seeds:
        rng = np.random.default_rng([int(s), 1])
        if kind == "field":
            runs.append(field_path(
                rng, duration, straight_s=v.get("straight_s", (30, 90)), turn_deg=v.get("turn_deg", (180, 360)),
                turn_rate_dps=v.get("turn_rate_dps", (5, 10)), cruise_mps=v.get("cruise_mps", (2.5, 4.0)),
                turn_speed_mps=v.get("turn_speed_mps", (1.5, 2.5)),
                turn_direction=v.get("turn_direction", "random"), first_straight_s=v.get("first_straight_s"),
                yaw_ramp=v.get("yaw_ramp_s", 3.0), speed_ramp=v.get("speed_ramp_s", 4.0)))
        elif kind == "straight":
            runs.append(straight_path(rng, duration, cruise_mps=v.get("cruise_mps", (2.5, 4.0)),
                                      hold_s=v.get("straight_s", (30, 90)), speed_ramp=v.get("speed_ramp_s", 4.0)))
        else:
            raise InvalidParameterError(f"path kind must be 'field' or 'straight', not {kind!r}")
    # terrain drawn per run from its own stream, then stacked
    paths = [stack_paths([r], duration, np.random.default_rng([int(s), 2]), yaw_ramp=v.get("yaw_ramp_s", 3.0),
                         speed_ramp=v.get("speed_ramp_s", 4.0), lean_deg_per_mps2=v.get("lean_deg_per_mps2", 1.5),
                         terrain_terms=v.get("terrain_terms", 3), terrain_amp_deg=v.get("terrain_amp_deg", (0.2, 0.8)),
                         terrain_period_s=v.get("terrain_period_s", (20, 90))) for r, s in zip(runs, seeds)]
    return _concat_paths(paths, duration)


def _concat_paths(paths: list[Path], duration) -> Path:
    def cat(name, fill):
        arrs = [getattr(p, name) for p in paths]
        width = max(a.shape[1] for a in arrs)
        return np.concatenate([np.pad(a, ((0, 0), (0, width - a.shape[1])), constant_values=fill) for a in arrs])

    p0 = paths[0]
    return Path(duration=float(duration), psi0=np.concatenate([p.psi0 for p in paths]),
                v0=np.concatenate([p.v0 for p in paths]), yaw_t=cat("yaw_t", duration + 1e6),
                yaw_dr=cat("yaw_dr", 0.0), speed_t=cat("speed_t", duration + 1e6), speed_dv=cat("speed_dv", 0.0),
                roll_terrain=np.concatenate([p.roll_terrain for p in paths]),
                pitch_terrain=np.concatenate([p.pitch_terrain for p in paths]),
                yaw_ramp=p0.yaw_ramp, speed_ramp=p0.speed_ramp, lean=p0.lean)


def _run_seeds(cfg, scenario: str, n: int) -> np.ndarray:
    base = np.random.SeedSequence([int(cfg.get("seed", 0)), sum(map(ord, scenario))])
    return np.array([c.generate_state(1)[0] for c in base.spawn(n)], dtype=np.int64)


def _truth_biases(cfg, seeds, accel_range=None):
    imu = cfg.get("imu", {})
    bg, ba = [], []
    for s in seeds:
        rng = np.random.default_rng([int(s), 3])
        bg.append(_signed_uniform(rng, imu.get("gyro_bias_dps", (0.05, 0.15)), 3) * DEG)
        ba.append(_signed_uniform(rng, accel_range or imu.get("accel_bias_mps2", (0.1, 0.3)), 3))
    return np.array(bg), np.array(ba)


@dataclass(frozen=True)
class ScenarioBatch:
    """A :class:`VehicleBatch` with one row of group labels per run."""

    batch: VehicleBatch
    groups: pd.DataFrame


def build_scenario(cfg: dict, scenario: str) -> ScenarioBatch:
    """The runs of one scenario: ``field``, ``straight``, ``artificial`` or ``sweep``.

    * ``field`` / ``straight``: ``scenarios.<name>.runs`` runs on field / straight paths,
      biases drawn from ``imu.gyro_bias_dps`` / ``imu.accel_bias_mps2`` (magnitudes,
      random signs), installation angles ``scenarios.<name>.installation_deg`` (default 0).
    * ``artificial``: the paper's accelerometer test.  Each run has small "intrinsic"
      accelerometer biases (``intrinsic_accel_bias_mps2``) and random installation angles
      up to ``installation_deg``; it is simulated twice with the same noise, without
      (``variant = plain``) and with the known ``artificial_accel_bias_mps2`` added.
    * ``sweep``: ``sweep.runs`` runs for every installation angle in ``sweep.angles_deg``
      and every ``sweep.kinds`` (``roll_pitch``: roll = pitch = angle; ``yaw``: yaw = angle;
      ``all``: roll = pitch = yaw = angle); the same paths, biases and noise at every angle.
    * ``observability``: pairs of runs on field paths that differ only by a known shift
      ``accel_shift_mps2`` of the accelerometer biases (same noise), for
      :func:`observability_table`.
    """
    mc = cfg.get("monte_carlo", {})
    sens = sensor_spec(cfg)
    if scenario == "sweep":
        return _sweep_scenario(cfg, sens, mc)
    sc = cfg.get("scenarios", {}).get(scenario)
    if sc is None:
        raise InvalidParameterError(f"no scenario {scenario!r} in the config")
    n = int(sc.get("runs", 10))
    duration = float(sc.get("duration_s", mc.get("duration_s", 1800)))
    seeds = _run_seeds(cfg, scenario, n)
    if scenario == "artificial":
        return _artificial_scenario(cfg, sc, sens, seeds, duration)
    if scenario == "observability":
        return _observability_scenario(cfg, sc, sens, seeds, duration)
    bg, ba = _truth_biases(cfg, seeds)
    ang = np.asarray(sc.get("installation_deg", (0.0, 0.0, 0.0)), dtype=float) * np.ones(3)
    mis = np.repeat(installation_dcm(*ang)[None], n, axis=0)
    path = _paths(cfg, sc.get("path", scenario), seeds, duration)
    return ScenarioBatch(VehicleBatch(path, sens, mis, bg, ba, seeds), pd.DataFrame({"run": range(n)}))


def _sweep_scenario(cfg: dict, sens, mc: dict) -> ScenarioBatch:
    """:func:`build_scenario`'s ``sweep``: the same runs at every installation angle and kind."""
    sw = cfg.get("sweep", {})
    n = int(sw.get("runs", 10))
    duration = float(sw.get("duration_s", mc.get("duration_s", 1800)))
    seeds0 = _run_seeds(cfg, "sweep", n)
    angles = [float(a) for a in sw.get("angles_deg", (0, 5, 10, 15, 20))]
    kinds = list(sw.get("kinds", ("roll_pitch", "yaw")))
    rows, seeds, mis = [], [], []
    for kind in kinds:
        if kind not in ("roll_pitch", "yaw", "all"):
            raise InvalidParameterError(f"sweep kind must be roll_pitch, yaw or all, not {kind!r}")
        for a in angles:
            for i, s in enumerate(seeds0):
                rp = a if kind in ("roll_pitch", "all") else 0.0
                y = a if kind in ("yaw", "all") else 0.0
                rows.append({"kind": kind, "angle_deg": a, "run": i})
                seeds.append(s)
                mis.append(installation_dcm(rp, rp, y))
    seeds = np.array(seeds)
    bg, ba = _truth_biases(cfg, seeds)
    path = _paths(cfg, sw.get("path", "field"), seeds, duration)
    batch = VehicleBatch(path, sens, np.array(mis), bg, ba, seeds)
    return ScenarioBatch(batch, pd.DataFrame(rows))


def _artificial_scenario(cfg: dict, sc: dict, sens, seeds, duration: float) -> ScenarioBatch:
    """:func:`build_scenario`'s ``artificial``: each run without and with the known biases added."""
    n = len(seeds)
    bg, ba = _truth_biases(cfg, seeds, accel_range=sc.get("intrinsic_accel_bias_mps2", (0.0, 0.04)))
    ba[:, 2] = _truth_biases(cfg, seeds)[1][:, 2]
    lim = float(sc.get("installation_deg", 2.0))
    mis = np.array([installation_dcm(*np.random.default_rng([int(s), 4]).uniform(-lim, lim, 3)) for s in seeds])
    art = np.zeros(3)
    art[:2] = sc.get("artificial_accel_bias_mps2", (0.2, -0.2))
    path = _paths(cfg, sc.get("path", "field"), np.concatenate([seeds, seeds]), duration)
    batch = VehicleBatch(path, sens, np.concatenate([mis, mis]), np.concatenate([bg, bg]),
                         np.concatenate([ba, ba + art]), np.concatenate([seeds, seeds]))
    groups = pd.DataFrame({"variant": ["plain"] * n + ["artificial"] * n, "run": list(range(n)) * 2,
                           "artificial_x": [0.0] * n + [art[0]] * n, "artificial_y": [0.0] * n + [art[1]] * n})
    return ScenarioBatch(batch, groups)


def _observability_scenario(cfg: dict, sc: dict, sens, seeds, duration: float) -> ScenarioBatch:
    """:func:`build_scenario`'s ``observability``: pairs of runs apart only by a known accelerometer-bias shift."""
    n = len(seeds)
    bg, ba = _truth_biases(cfg, seeds)
    shift = np.zeros(3)
    shift[:2] = sc.get("accel_shift_mps2", (0.2, -0.2))
    path = _paths(cfg, sc.get("path", "field"), np.concatenate([seeds, seeds]), duration)
    eye = np.repeat(np.eye(3)[None], 2 * n, axis=0)
    batch = VehicleBatch(path, sens, eye, np.concatenate([bg, bg]), np.concatenate([ba, ba + shift]),
                         np.concatenate([seeds, seeds]))
    groups = pd.DataFrame({"variant": ["plain"] * n + ["shifted"] * n, "run": list(range(n)) * 2})
    return ScenarioBatch(batch, groups)


# ----------------------------------------------------------------------------- running


def simulate(batch: VehicleBatch, params: TereshkovParams, chunk_s: float = 10.0,
             record_every_s: float = 1.0) -> tuple[TereshkovResult, dict]:
    """Stream the sensor data of ``batch`` through the estimator.

    Returns the decimated :class:`TereshkovResult` and timing information
    (``wall_s``: total; ``estimator_s``: the estimator loop alone; ``steps``).
    """
    dt = 1.0 / batch.sensors.imu_rate
    rec = max(1, int(round(record_every_s / dt)))
    chunk_s = max(rec * dt, round(chunk_s / (rec * dt)) * rec * dt)
    parts, state = [], None
    t0 = time.perf_counter()
    est_s = 0.0
    for ch in sensor_chunks(batch, chunk_s):
        t1 = time.perf_counter()
        res, state = run_estimator(ch.gyro, ch.accel, ch.f_ext, ch.course, ch.speed, dt, params, state, rec)
        est_s += time.perf_counter() - t1
        parts.append(res)
    wall = time.perf_counter() - t0
    return concat_results(parts), {"wall_s": wall, "estimator_s": est_s, "steps": batch.n_steps,
                                   "runs": batch.n_runs}


def equivalent_accel_bias(accel_bias, C_bs) -> np.ndarray:
    """The x, y accelerometer biases that, with a zero z bias, tilt the platform as the true
    biases do when the vehicle is level: ``b'_xy = b_xy + C_bs[:2,:2]⁻¹ C_bs[:2,2] b_z``.

    The estimator has no z-accelerometer term, so under a tilted installation it converges
    to these (the z bias leaks in as ``b_z sin α``); for an untilted installation (any yaw)
    they equal the sensor-axis biases.  Shapes (R, 3), (R, 3, 3) -> (R, 2).
    """
    b = np.asarray(accel_bias, dtype=float)
    C = np.asarray(C_bs, dtype=float)
    leak = np.linalg.solve(C[:, :2, :2], C[:, :2, 2:3])[..., 0] * b[:, 2:3]
    return b[:, :2] + leak


def attitude_errors(batch: VehicleBatch, res: TereshkovResult) -> np.ndarray:
    """Platform attitude errors ``θ`` (R, m, 3) [rad] at the record times: ``C_est C_trueᵀ ≈ I + θ̃``
    in NED (θ_N, θ_E: tilt; θ_D: heading), ``C_true = C_nb C_bs``."""
    st = vehicle_state(batch.path, res.t, batch.sensors.g)
    C_true = st.C_nb @ batch.C_bs[:, None]
    E = res.C @ np.swapaxes(C_true, -1, -2)
    return 0.5 * np.stack([E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0], E[..., 1, 0] - E[..., 0, 1]], -1)


def tidy(sb: ScenarioBatch, res: TereshkovResult, scenario: str, every_s: float = 1.0) -> pd.DataFrame:
    """One row per run × time × sensor × axis (x, y).

    Sensors: ``gyro`` [°/s] and ``accel`` [m/s²] (estimate, truth, error = estimate - truth;
    ``truth_eq``/``error_eq`` against :func:`equivalent_accel_bias`, the same as
    truth/error for the gyro), and ``attitude`` [°]: the platform tilt errors about
    north (x) and east (y) (truth 0).  ``update_time`` [s] is the time the estimate
    has been updating so far (elapsed time for the attitude).
    """
    b = sb.batch
    dt_rec = res.t[1] - res.t[0] if len(res.t) > 1 else 1.0
    step = max(1, int(round(every_s / dt_rec)))
    idx = np.arange(0, len(res.t), step)
    t = res.t[idx]
    R, m = b.n_runs, len(idx)
    eq = np.concatenate([equivalent_accel_bias(b.accel_bias, b.C_bs), b.accel_bias[:, 2:]], axis=1)
    att = attitude_errors(b, res)[:, idx]
    elapsed = np.broadcast_to(t, (R, m))
    frames = []
    for sensor, est, truth, truth_eq, upd, scale in (
        ("gyro", res.gyro_bias[:, idx], b.gyro_bias, b.gyro_bias, res.gyro_time[:, idx], 1 / DEG),
        ("accel", res.accel_bias[:, idx], b.accel_bias, eq, res.accel_time[:, idx], 1.0),
        ("attitude", att, np.zeros((R, 3)), np.zeros((R, 3)), elapsed, 1 / DEG),
    ):
        for a, ax in enumerate(AXES):
            e = est[:, :, a] * scale
            tr = np.repeat(truth[:, a, None] * scale, m, axis=1)
            tq = np.repeat(truth_eq[:, a, None] * scale, m, axis=1)
            frames.append(pd.DataFrame({
                "row": np.repeat(np.arange(R), m), "t": np.tile(t, R), "sensor": sensor, "axis": ax,
                "estimate": e.ravel(), "truth": tr.ravel(), "error": (e - tr).ravel(),
                "truth_eq": tq.ravel(), "error_eq": (e - tq).ravel(), "update_time": upd.ravel()}))
    df = pd.concat(frames, ignore_index=True)
    groups = sb.groups.reset_index(drop=True)
    df = df.join(groups, on="row").drop(columns="row")
    df.insert(0, "scenario", scenario)
    return df


def run_scenario(cfg: dict, scenario: str) -> tuple[pd.DataFrame, dict]:
    """Build, simulate and tabulate one scenario; returns (tidy table, timing)."""
    return run_scenarios(cfg, [scenario])[scenario]


def _concat_batches(batches: list[VehicleBatch]) -> VehicleBatch:
    return VehicleBatch(_concat_paths([b.path for b in batches], batches[0].path.duration), batches[0].sensors,
                        np.concatenate([b.C_bs for b in batches]), np.concatenate([b.gyro_bias for b in batches]),
                        np.concatenate([b.accel_bias for b in batches]), np.concatenate([b.seeds for b in batches]))


def _take_runs(res: TereshkovResult, idx) -> TereshkovResult:
    return replace(res, gyro_bias=res.gyro_bias[idx], accel_bias=res.accel_bias[idx], u=res.u[idx],
                   mode=res.mode[idx], mode_time=res.mode_time[idx], gyro_time=res.gyro_time[idx],
                   accel_time=res.accel_time[idx], C=res.C[idx])


def job_share(sb: ScenarioBatch, job: int, jobs: int) -> ScenarioBatch:
    """The rows of ``sb`` whose run number ``r`` has ``r % jobs == job`` (every variant,
    angle and kind of those runs), with their row number in the whole batch in the
    ``batch_row`` column, so that :func:`merge_job_tables` restores the order of one job.

    Each run draws its noise from its own seed (:class:`VehicleBatch`), so a run's
    numbers do not depend on the job it is in.
    """
    if not 0 <= job < jobs:
        raise InvalidParameterError(f"job {job} is not in 0 .. {jobs - 1}")
    idx = np.flatnonzero(sb.groups["run"].to_numpy() % jobs == job)
    b = sb.batch
    batch = VehicleBatch(b.path.take(idx), b.sensors, b.C_bs[idx], b.gyro_bias[idx], b.accel_bias[idx], b.seeds[idx])
    return ScenarioBatch(batch, sb.groups.iloc[idx].assign(batch_row=idx).reset_index(drop=True))


def merge_job_tables(tables) -> pd.DataFrame:
    """The tidy tables of the jobs of one scenario (:func:`job_share`) as one table, in
    the order one job writes: sensor, axis, row of the whole batch, time."""
    df = pd.concat(list(tables), ignore_index=True)
    if "batch_row" not in df:
        raise InvalidParameterError("the job tables have no batch_row column (not made by job_share)")
    sensor = df["sensor"].map({s: i for i, s in enumerate(SENSORS + ("attitude",))})
    order = np.lexsort((df["t"].to_numpy(), df["batch_row"].to_numpy(), df["axis"].to_numpy(), sensor.to_numpy()))
    return df.iloc[order].drop(columns="batch_row").reset_index(drop=True)


def merge_job_timings(timings: pd.DataFrame) -> pd.DataFrame:
    """Wall times of the jobs of each scenario summed (``jobs``: how many): the compute
    cost of the Monte Carlo, whatever the split."""
    cols = ["runs", "wall_s", "estimator_s", "tidy_s"]
    first = timings.groupby("scenario", sort=False).first().drop(columns=cols)
    out = timings.groupby("scenario", sort=False)[cols].sum().join(first)
    out["jobs"] = timings.groupby("scenario", sort=False).size()
    return out.reset_index()[["scenario"] + [c for c in timings.columns if c != "scenario"] + ["jobs"]]


def run_scenarios(cfg: dict, scenarios, job: int = 0, jobs: int | None = None) -> dict[str, tuple[pd.DataFrame, dict]]:
    """Several scenarios (names as in :func:`build_scenario`, ``sweep`` included) through
    one estimator loop per run duration: the loop costs per step, not per run, so
    batching scenarios together is cheaper than running them one after the other.

    With ``jobs`` given, only the share ``job`` of the runs (:func:`job_share`; the tables
    have a ``batch_row`` column for :func:`merge_job_tables`).

    Returns ``{scenario: (tidy table, timing)}``; the timing of a merged loop is
    reported for each of its scenarios (with ``merged_with``).
    """
    mc = cfg.get("monte_carlo", {})
    params = estimator_params(cfg)
    built = {name: build_scenario(cfg, name) for name in scenarios}
    if jobs is not None:
        built = {name: job_share(sb, job, jobs) for name, sb in built.items()}
    by_duration: dict[float, list[str]] = {}
    for name, sb in built.items():
        by_duration.setdefault(sb.batch.path.duration, []).append(name)
    out = {}
    for names in by_duration.values():
        batch = _concat_batches([built[n].batch for n in names])
        res, timing = simulate(batch, params, mc.get("chunk_s", 10.0), mc.get("record_every_s", 1.0))
        start = 0
        for n in names:
            R = built[n].batch.n_runs
            t0 = time.perf_counter()
            df = tidy(built[n], _take_runs(res, slice(start, start + R)), n, mc.get("table_every_s", 1.0))
            out[n] = (df, timing | {"scenario": n, "merged_with": "+".join(names),
                                    "tidy_s": time.perf_counter() - t0})
            start += R
    return out


def heading_table(cfg: dict, scenario: str = "field", runs: int = 2, every_s: float = 1.0) -> pd.DataFrame:
    """True heading and yaw rate of the first ``runs`` runs of a scenario (Fig. 2)."""
    sb = build_scenario(cfg, scenario)
    path = sb.batch.path.take(np.arange(min(runs, sb.batch.n_runs)))
    t = np.arange(0.0, path.duration + 1e-9, every_s)
    st = vehicle_state(path, t, sb.batch.sensors.g)
    rows = []
    for i in range(path.n_runs):
        rows.append(pd.DataFrame({"scenario": scenario, "run": i, "t": t,
                                  "heading_deg": np.degrees(st.heading[i]) % 360.0,
                                  "yaw_rate_dps": np.degrees(st.yaw_rate[i]), "speed_mps": st.speed[i],
                                  "roll_deg": np.degrees(st.roll[i]), "pitch_deg": np.degrees(st.pitch[i])}))
    return pd.concat(rows, ignore_index=True)


# ----------------------------------------------------------------------------- metrics


def error_curves(df: pd.DataFrame, by=("scenario",), error: str = "error") -> pd.DataFrame:
    """Monte Carlo mean |error|, RMS error and mean update time per group × sensor × time."""
    keys = list(by) + ["sensor", "t"]
    g = df.assign(abs_error=df[error].abs(), sq=df[error] ** 2).groupby(keys, sort=True)
    out = g.agg(mean_abs_error=("abs_error", "mean"), ms=("sq", "mean"), update_time=("update_time", "mean"))
    out["rms_error"] = np.sqrt(out.pop("ms"))
    return out.reset_index()


def convergence_time(t, e, e_ss: float, fraction: float = 0.05) -> float:
    """First time after which ``e - e_ss ≤ fraction (e[0] - e_ss)`` holds at every later sample."""
    t = np.asarray(t, dtype=float)
    e = np.asarray(e, dtype=float)
    if len(t) == 0 or not np.isfinite(e_ss) or e[0] <= e_ss:
        return float("nan")
    ok = e - e_ss <= fraction * (e[0] - e_ss)
    bad = np.flatnonzero(~ok)
    if len(bad) == 0:
        return float(t[0])
    if bad[-1] == len(t) - 1:
        return float("nan")
    return float(t[bad[-1] + 1])


def convergence_summary(df: pd.DataFrame, steady_state_from_s: float, fraction: float = 0.05,
                        nonconvergence_ratio: float = 0.5, by=("scenario",), error: str = "error") -> pd.DataFrame:
    """Per group × sensor: ``e0``, ``e_ss`` (mean |error|), ``ss_rms``, ``t_conv`` [s],
    ``update_time_at_conv`` [s], ``final_ratio`` (E_ss / E(0)), ``converged``, runs.

    ``error`` names the error column (``error``: against the sensor-axis truth;
    ``error_eq``: against the equivalent biases).
    """
    curves = error_curves(df, by, error)
    rows = []
    keys = list(by) + ["sensor"]
    for key, c in curves.groupby(keys, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        sub = df
        for k, v in zip(keys, key):
            sub = sub[sub[k] == v]
        ss = c["t"] >= steady_state_from_s
        e0 = float(c["mean_abs_error"].iloc[0])
        e_ss = float(c.loc[ss, "mean_abs_error"].mean())
        ss_rms = float(np.sqrt((sub.loc[sub["t"] >= steady_state_from_s, error] ** 2).mean()))
        converged = bool(e_ss <= nonconvergence_ratio * e0)
        tc = convergence_time(c["t"], c["mean_abs_error"], e_ss, fraction) if converged else float("nan")
        upd = float(np.interp(tc, c["t"], c["update_time"])) if np.isfinite(tc) else float("nan")
        rows.append(dict(zip(keys, key)) | {
            "e0": e0, "e_ss": e_ss, "ss_rms": ss_rms, "t_conv": tc, "update_time_at_conv": upd,
            "final_ratio": e_ss / e0 if e0 > 0 else float("nan"), "converged": converged,
            "update_fraction": float(c["update_time"].iloc[-1] / max(c["t"].iloc[-1], 1e-9)),
            "runs": int(sub.groupby([k for k in ("run", "variant", "kind", "angle_deg") if k in sub]).ngroups),
        })
    return pd.DataFrame(rows)


def artificial_summary(df: pd.DataFrame, steady_state_from_s: float) -> pd.DataFrame:
    """The paper's artificial-bias test, per axis and overall (accelerometer only).

    ``rms_vs_artificial``: RMS of (estimate with artificial biases - artificial bias),
    the comparison of the paper's Fig. 4 (it includes the unknown intrinsic bias);
    ``rms_difference``: RMS of (estimate with - estimate without - artificial bias);
    ``rms_vs_truth``: RMS of (estimate with - total true bias).
    """
    a = df[(df["sensor"] == "accel") & (df["t"] >= steady_state_from_s)]
    w = a[a["variant"] == "artificial"].set_index(["run", "t", "axis"])
    p = a[a["variant"] == "plain"].set_index(["run", "t", "axis"])
    art = np.where(w.index.get_level_values("axis") == "x", w["artificial_x"], w["artificial_y"])
    d = pd.DataFrame({"axis": w.index.get_level_values("axis"),
                      "vs_artificial": w["estimate"].to_numpy() - art,
                      "difference": (w["estimate"] - p["estimate"].reindex(w.index)).to_numpy() - art,
                      "vs_truth": w["error"].to_numpy()})
    rows = []
    for ax, s in list(d.groupby("axis")) + [("xy", d)]:
        rows.append({"axis": ax, **{f"rms_{c}": float(np.sqrt((s[c] ** 2).mean()))
                                    for c in ("vs_artificial", "difference", "vs_truth")}})
    return pd.DataFrame(rows)



def sweep_summary(df: pd.DataFrame, steady_state_from_s: float, fraction: float = 0.05,
                  nonconvergence_ratio: float = 0.5) -> pd.DataFrame:
    """:func:`convergence_summary` per installation kind × angle, against the sensor-axis
    truth (``reference = sensor_axes``) and the equivalent biases (``reference = equivalent``)."""
    out = []
    for ref, col in (("sensor_axes", "error"), ("equivalent", "error_eq")):
        s = convergence_summary(df, steady_state_from_s, fraction, nonconvergence_ratio, by=("kind", "angle_deg"),
                                error=col)
        s.insert(0, "reference", ref)
        out.append(s)
    return pd.concat(out, ignore_index=True)


def observability_table(cfg: dict) -> tuple[pd.DataFrame, dict]:
    """How much the residual torque ``u`` depends on the accelerometer bias, per motion mode.

    Pairs of runs differ only by a known accelerometer-bias shift Δ (same path, noise and
    gyro biases); the accelerometer estimate is frozen (``update_accel=False``), so the
    difference ``Δu`` of the torques is the deterministic effect of Δ.  Per run and mode
    (settled straight samples, settled turning samples): ``du_rms`` [°/s], RMS of
    ``|Δu_xy|``; ``predicted_rms`` [°/s] from eq. (13) with the true yaw rate (zero in
    straight motion by eq. 12); ``sensitivity`` = ``du_rms / |Δ|`` [(°/s)/(m/s²)].
    """
    mc = cfg.get("monte_carlo", {})
    sb = build_scenario(cfg, "observability")
    params = replace(estimator_params(cfg), update_accel=False)
    res, timing = simulate(sb.batch, params, mc.get("chunk_s", 10.0), mc.get("record_every_s", 1.0))
    timing["scenario"] = "observability"
    g = sb.groups
    plain = np.flatnonzero(g["variant"].to_numpy() == "plain")
    shifted = np.flatnonzero(g["variant"].to_numpy() == "shifted")
    delta = sb.batch.accel_bias[shifted] - sb.batch.accel_bias[plain]
    du = (res.u[shifted] - res.u[plain])[..., :2]
    # eq. (13) prediction with the true sensor-frame rate (level platform, k_b = k_p)
    st = vehicle_state(sb.batch.path.take(plain), res.t, sb.batch.sensors.g)
    C_sb = np.swapaxes(sb.batch.C_bs[plain], -1, -2)
    w = np.einsum("rij,rnj->rni", C_sb, st.omega_b)
    w[..., :2] = 0.0  # eq. (14) setting: only the vertical rate
    pred = steady_state_torque(np.zeros_like(w), np.broadcast_to(delta[:, None, :], w.shape), w, params)[..., :2]
    mode, mt = res.mode[plain], res.mode_time[plain]
    rows = []
    for name, code, settle in (("straight", 0, params.straight_settle_s), ("turn", 1, params.turn_settle_s)):
        sel = (mode == code) & (mt >= settle)
        for i in range(len(plain)):
            s_ = sel[i]
            if not s_.any():
                continue
            d = np.sqrt((du[i, s_] ** 2).sum(-1).mean()) / DEG
            pr = np.sqrt((pred[i, s_] ** 2).sum(-1).mean()) / DEG
            mag = float(np.linalg.norm(delta[i, :2]))
            rows.append({"run": i, "mode": name, "samples": int(s_.sum()), "du_rms_dps": float(d),
                         "predicted_rms_dps": float(pr), "shift_mps2": mag, "sensitivity": float(d / mag)})
    return pd.DataFrame(rows), timing
