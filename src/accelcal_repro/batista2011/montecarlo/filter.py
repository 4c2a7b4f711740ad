"""The filter experiments of Batista et al. (2011), Sec. V-B: the scenario (trajectory, truth,
noise levels), the Monte Carlo over sensor noise on a shared trajectory and the merge of its
chunks, one exact run, the cost per step and the error budget per noise source."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal.batista.filter import PAPER_THETA, PAPER_XI, STATES, covariance_sequence, kalman_filter
from ..trajectory import Attitude, motion_signals
from .shared_gain import _FilterState, shared_gain_filter


@dataclass(frozen=True)
class FilterScenario:
    """A simulated filter experiment: trajectory, true signals and noise levels."""

    attitude: Attitude
    signals: dict
    bias: np.ndarray  # (3,) m/s²
    noise_acc: float  # m/s²
    noise_gyro: float  # rad/s
    noise_vel: float  # m/s

    @property
    def t(self) -> np.ndarray:
        return self.attitude.t

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    def x_true(self) -> np.ndarray:
        """True state ``(v, g, b)`` at every sample, (n, 9)."""
        s = self.signals
        return np.hstack([s["v"], s["g"], np.broadcast_to(self.bias, s["v"].shape)])


def filter_scenario(attitude: Attitude, bias, noise_acc, noise_gyro_deg_s, noise_vel, g=9.81,
                    lever_arm=(0.0, 0.0, 0.0)) -> FilterScenario:
    """Truth for the filter: NED gravity of magnitude ``g`` and a sensor at ``lever_arm``."""
    sig = motion_signals(attitude, [0.0, 0.0, float(g)], lever_arm)
    return FilterScenario(attitude, sig, np.asarray(bias, float), float(noise_acc),
                          float(np.deg2rad(noise_gyro_deg_s)), float(noise_vel))


def _measurements(sc: FilterScenario, idx: np.ndarray, rngs):
    """Noisy ``a_m``, ``ω_m`` and ``y`` at sample indices ``idx``, one run per generator in
    ``rngs``, each (runs, len, 3).  Consecutive calls continue each run's stream."""
    s = sc.signals
    z = np.stack([g.standard_normal((3, len(idx), 3)) for g in rngs])  # (runs, a|ω|y, len, 3)
    a = s["a"][idx] + sc.bias + sc.noise_acc * z[:, 0]
    w = sc.attitude.omega[idx] + sc.noise_gyro * z[:, 1]
    y = s["v"][idx] + sc.noise_vel * z[:, 2]
    return a, w, y


def initial_estimate(a0, y0) -> np.ndarray:
    """Sec. V-B: velocity from its measurement, gravity from the accelerometer (``ĝ = -a_m``), bias 0."""
    a0, y0 = np.asarray(a0, float), np.asarray(y0, float)
    return np.concatenate([y0, -a0, np.zeros_like(a0)], axis=-1)



@dataclass(frozen=True)
class FilterMonteCarlo:
    """Results of :func:`filter_montecarlo`.

    ``runs``: one row per run × recorded time (errors ``e_<state>`` = estimate − truth);
    ``summary``: one row per summary time × state (``mean_error``, ``std_error``,
    ``rms_error``, ``filter_sigma``, ``run0_error``: the error of the lowest-numbered
    run, ``n_runs``); ``moments``: the same statistics in mergeable form (see
    :func:`merge_filter_moments`); ``P``: the filter covariance at the times of
    ``runs`` (n_rec, 9, 9).
    """

    runs: pd.DataFrame
    summary: pd.DataFrame
    moments: pd.DataFrame
    P: np.ndarray


def filter_montecarlo(sc: FilterScenario, rngs, P0_diag, xi=PAPER_XI, theta=PAPER_THETA,
                      record_every_s: float = 2.0, summary_every_s: float = 0.1, block: int = 500,
                      sub_block: int = 25, covariance=None, run_ids=None) -> FilterMonteCarlo:
    """Monte Carlo of the filter over sensor noise on a shared trajectory.

    Every run draws its own accelerometer, gyro and velocity noise from its own
    generator (``rngs``, one per run, :func:`run_streams`); its initial estimate is
    :func:`initial_estimate` of its first samples.  ``run_ids`` numbers the runs in the
    tables (default ``0 .. len(rngs) - 1``): a chunk of a larger Monte Carlo passes its
    runs' numbers and streams, and :func:`merge_filter_moments` combines the chunks.

    The covariance recursion of the Kalman filter depends on the data only through
    ``ω`` in ``A(t)``.  Along a shared trajectory it is computed once (along the true
    ``ω``) and the gain sequence is applied to every run; each run still propagates its
    state with its own gyro readings.  With gyro noise of 0.05 °/s against rates of
    tens of °/s the per-run gains would differ by well under 1 %; the tests check the
    estimates against :func:`~accelcal.batista.filter.kalman_filter` (own covariance).
    ``covariance`` may pass that sequence in (the output of
    ``covariance_sequence(..., return_covariance=True)`` for this trajectory and tuning).

    Returns
    -------
    FilterMonteCarlo
    """
    runs = len(rngs)
    ids = np.arange(runs) if run_ids is None else np.asarray(run_ids, int)
    if runs == 0 or len(ids) != runs:
        raise ValueError(f"{len(ids)} run ids for {runs} random streams (need at least one run)")
    t, dt = sc.t, sc.dt
    n = len(t)
    if covariance is None:
        covariance = covariance_sequence(t, sc.attitude.omega, np.asarray(P0_diag, float), xi, theta,
                                         return_covariance=True)
    gains, _, P_all = covariance
    rec = np.unique(np.round(np.arange(0, t[-1] + 1e-9, record_every_s) / dt).astype(int))
    summ = np.unique(np.round(np.arange(0, t[-1] + 1e-9, summary_every_s) / dt).astype(int))
    rec, summ = rec[rec < n], summ[summ < n]
    both = np.union1d(rec, summ)
    a, w, y = _measurements(sc, np.array([0]), rngs)
    st = _FilterState(initial_estimate(a[:, 0], y[:, 0]), a[:, 0], w[:, 0], both, dt)
    for k0 in range(1, n, block):
        idx = np.arange(k0, min(k0 + block, n))
        a, w, y = _measurements(sc, idx, rngs)
        for j0 in range(0, len(idx), sub_block):  # small sub-blocks keep the (B, 3, 3, T) arrays in cache
            sl = slice(j0, j0 + sub_block)
            st.run_block(a[:, sl], w[:, sl], y[:, sl], gains, k0 + j0)
    return _filter_tables(st.out - sc.x_true()[both][None], ids, t, rec, summ, both, P_all)


def _filter_tables(err, ids, t, rec, summ, both, P_all) -> FilterMonteCarlo:
    """:func:`filter_montecarlo`'s tables from the errors ``err`` (runs, times ``both``, 9):
    the recorded errors per run, and the moments and summary at the summary times."""
    runs = len(ids)
    pos = {k: i for i, k in enumerate(both)}
    ri = [pos[k] for k in rec]
    si = [pos[k] for k in summ]
    per_run = pd.DataFrame({"run": np.repeat(ids, len(rec)), "t": np.tile(t[rec], runs)})
    for j, s in enumerate(STATES):
        per_run[f"e_{s}"] = err[:, ri, j].ravel()
    e = err[:, si]
    mean = e.mean(axis=0)
    first = int(np.argmin(ids))
    moments = pd.DataFrame({
        "t": np.repeat(t[summ], 9), "state": np.tile(STATES, len(summ)), "n": runs,
        "mean": mean.ravel(), "m2": ((e - mean) ** 2).sum(axis=0).ravel(),
        "first_run": int(ids[first]), "first_error": e[first].ravel(),
        "filter_sigma": np.sqrt(np.einsum("kii->ki", P_all[summ])).ravel(),
    })
    return FilterMonteCarlo(runs=per_run, summary=filter_summary(moments), moments=moments, P=P_all[rec])


def merge_filter_moments(parts) -> pd.DataFrame:
    """Combine the ``moments`` of chunks of one Monte Carlo (disjoint runs, same times).

    Means and sums of squared deviations combine exactly (Chan et al.'s pairwise
    update), so the merged statistics equal those of one job over all runs up to
    rounding (~1e-16 relative).
    """
    parts = list(parts)
    if not parts:
        raise ValueError("no Monte Carlo chunks to merge")
    key = parts[0][["t", "state"]].reset_index(drop=True)
    for p in parts[1:]:
        if len(p) != len(key) or not (p["state"].to_numpy() == key["state"].to_numpy()).all() \
                or not np.array_equal(p["t"].to_numpy(), key["t"].to_numpy()):
            raise ValueError("Monte Carlo chunks with different summary times cannot be merged")
    n_i = np.stack([p["n"].to_numpy(float) for p in parts])
    mean_i = np.stack([p["mean"].to_numpy() for p in parts])
    n = n_i.sum(axis=0)
    mean = (n_i * mean_i).sum(axis=0) / n
    m2 = np.stack([p["m2"].to_numpy() for p in parts]).sum(axis=0) + (n_i * (mean_i - mean) ** 2).sum(axis=0)
    first = int(np.argmin([p["first_run"].iloc[0] for p in parts]))
    return key.assign(n=n.astype(int), mean=mean, m2=m2, first_run=parts[first]["first_run"].to_numpy(),
                      first_error=parts[first]["first_error"].to_numpy(),
                      filter_sigma=parts[0]["filter_sigma"].to_numpy())


def filter_summary(moments: pd.DataFrame) -> pd.DataFrame:
    """The per-time statistics over runs from (merged) ``moments``: columns ``t, state,
    mean_error, std_error, rms_error, filter_sigma, run0_error, n_runs``."""
    n = moments["n"].to_numpy(float)
    m2 = moments["m2"].to_numpy()
    mean = moments["mean"].to_numpy()
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(n > 1, np.sqrt(m2 / (n - 1)), np.nan)
    return pd.DataFrame({
        "t": moments["t"].to_numpy(), "state": moments["state"].to_numpy(), "mean_error": mean,
        "std_error": std, "rms_error": np.sqrt(m2 / n + mean**2), "filter_sigma": moments["filter_sigma"].to_numpy(),
        "run0_error": moments["first_error"].to_numpy(), "n_runs": moments["n"].to_numpy(),
    })


def filter_example(sc: FilterScenario, rng: np.random.Generator, P0_diag, xi=PAPER_XI, theta=PAPER_THETA,
                   record_every_s: float = 0.1) -> pd.DataFrame:
    """One run of the exact filter (own covariance from its own gyro readings), Figs. 4–5.

    Returns
    -------
    pandas.DataFrame
        Columns ``t, state, estimate, truth, sigma``.
    """
    idx = np.arange(len(sc.t))
    a, w, y = (m[0] for m in _measurements(sc, idx, [rng]))
    every = max(1, int(round(record_every_s / sc.dt)))
    r = kalman_filter(sc.t, a, w, y, initial_estimate(a[0], y[0]), np.asarray(P0_diag, float), xi, theta, every)
    truth = sc.x_true()[::every]
    return pd.DataFrame({"t": np.repeat(r.t, 9), "state": np.tile(STATES, len(r.t)), "estimate": r.x.ravel(),
                         "truth": truth.ravel(), "sigma": r.sigma.ravel()})


def filter_cost(sc: FilterScenario, rng: np.random.Generator, P0_diag, xi=PAPER_XI, theta=PAPER_THETA,
                steps: int = 3000, runs: int = 200, repeat: int = 3) -> pd.DataFrame:
    """Wall time per step: the exact single-run filter and the shared-gain batch per run.

    Returns
    -------
    pandas.DataFrame
        Columns ``implementation, runs, steps, seconds, us_per_step, us_per_run_step``
        (best of ``repeat``).
    """
    steps = min(steps, len(sc.t))
    t = sc.t[:steps]
    idx = np.arange(steps)
    a, w, y = _measurements(sc, idx, rng.spawn(runs))
    x0 = initial_estimate(a[:, 0], y[:, 0])
    P0 = np.asarray(P0_diag, float)

    def best(f):
        out = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            f()
            out.append(time.perf_counter() - t0)
        return min(out)

    single = best(lambda: kalman_filter(t, a[0], w[0], y[0], x0[0], P0, xi, theta))
    gains_t = best(lambda: covariance_sequence(t, sc.attitude.omega[:steps], P0, xi, theta))
    gains, _ = covariance_sequence(t, sc.attitude.omega[:steps], P0, xi, theta)
    batch = best(lambda: shared_gain_filter(sc.dt, a, w, y, x0, gains, [steps - 1]))
    rows = [("kalman_filter (own covariance, 1 run)", 1, single),
            ("covariance_sequence (shared gains)", 1, gains_t),
            ("shared_gain_filter (state only)", runs, batch)]
    return pd.DataFrame([{"implementation": name, "runs": r, "steps": steps, "seconds": s,
                          "us_per_step": 1e6 * s / steps, "us_per_run_step": 1e6 * s / (steps * r)}
                         for name, r, s in rows])


def filter_error_budget(sc: FilterScenario, rngs, P0_diag, steady_from_s: float, xi=PAPER_XI,
                        theta=PAPER_THETA) -> pd.DataFrame:
    """Steady-state RMS error per state with one noise source at a time (and all together),
    over ``len(rngs)`` runs (one generator per run; the sources are run one after the other).

    Returns
    -------
    pandas.DataFrame
        Columns ``source`` (``accelerometer``, ``gyro``, ``velocity``, ``all``),
        ``state``, ``rms_error`` (over runs and ``t >= steady_from_s``).
    """
    levels = {"accelerometer": (sc.noise_acc, 0.0, 0.0), "gyro": (0.0, sc.noise_gyro, 0.0),
              "velocity": (0.0, 0.0, sc.noise_vel), "all": (sc.noise_acc, sc.noise_gyro, sc.noise_vel)}
    frames = []
    cov = covariance_sequence(sc.t, sc.attitude.omega, np.asarray(P0_diag, float), xi, theta, return_covariance=True)
    for name, (na, ng, nv) in levels.items():
        one = FilterScenario(sc.attitude, sc.signals, sc.bias, na, ng, nv)
        mc = filter_montecarlo(one, rngs, P0_diag, xi, theta, record_every_s=sc.t[-1], summary_every_s=1.0,
                               covariance=cov)
        d = mc.summary[mc.summary["t"] >= steady_from_s]
        rms = d.groupby("state", sort=False)["rms_error"].apply(lambda r: float(np.sqrt(np.mean(r**2))))
        frames.append(pd.DataFrame({"source": name, "state": list(STATES),
                                    "rms_error": rms.reindex(STATES).to_numpy()}))
    return pd.concat(frames, ignore_index=True)


__all__ = ["FilterMonteCarlo", "FilterScenario", "filter_cost", "filter_error_budget", "filter_example",
           "filter_montecarlo", "filter_scenario", "filter_summary", "initial_estimate", "merge_filter_moments"]
