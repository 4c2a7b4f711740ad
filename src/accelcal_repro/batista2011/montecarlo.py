"""Monte Carlo experiments of Batista et al. (2011), Sec. V, as pure functions returning tidy tables.

* :func:`calibration_montecarlo`: Table I (and its linear-only variant, and the full
  LLS of Burkhard et al. 2024 on the window means) on simulated stepped-table data,
  one row per run × data set × method × parameter.
* :func:`calibration_bounds`: the CRLB of the design, and :func:`asymptotic_bias`:
  the estimator's own O(σ²) bias (errors in variables), one row per parameter.
* :func:`calibration_summary`, :func:`lls_comparison`: statistics over runs.
* :func:`filter_montecarlo`: the online filter on many noise realisations of a shared
  attitude trajectory, one row per run × (decimated) time sample, plus a summary over
  runs per time sample.
* :func:`filter_example`: one run of the exact filter (its own covariance), for Figs. 4–5.
* :func:`filter_error_budget`: steady-state errors with one noise source at a time.
* :func:`observability_table`, :func:`gramian_table`: errors along and across the
  rotation axis; the observability Gramian.
* :func:`filter_cost`: wall time per step of the filter.

Every random draw comes from the ``numpy.random.Generator`` passed in.  The Monte Carlos
take one generator per run (:func:`run_streams`), so that a run's numbers do not depend
on which other runs share its job: the workflow splits the runs into chunks (separate
jobs, e.g. on a cluster) and merges them (:func:`merge_filter_moments`) to the same
tables as one job would write.
"""

from __future__ import annotations

import time
import zlib
from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal.kernels import compiled
from accelcal.lls_batch import full_lls_batch
from accelcal.model import dM_dparams, params_from_m
from accelcal.uncertainty import crlb as lls_crlb
from accelcal.batista.calibration import PARAMETERS, WindowStatistics, calibrate_batch
from accelcal.batista.crlb import DERIVED, calibration_crlb, derived_quantities, pack
from accelcal.batista.filter import (
    PAPER_THETA,
    PAPER_XI,
    STATES,
    covariance_sequence,
    kalman_filter,
    observability_gramian,
    rotation_coefficients,
)
from accelcal.batista.model import accelerometer_output, euler_to_rotation, gravity_in_table, specific_force_at_rest
from .trajectory import Attitude, StepSchedule, motion_signals, stepped_attitudes

_LOWER = ([0, 1, 1, 2, 2, 2], [0, 0, 1, 0, 1, 2])


def stream(seed: int, name: str) -> np.random.Generator:
    """Independent random stream per experiment: derived from the master seed and a name."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def run_streams(seed: int, name: str, run_ids) -> list[np.random.Generator]:
    """One independent random stream per run: derived from the master seed, the
    experiment's name and the run's number (not from its position in a job)."""
    key = zlib.crc32(name.encode())
    return [np.random.default_rng([int(seed), key, int(r)]) for r in run_ids]


def _group(name: str) -> str:
    for g in ("F_inv", "b_prime", "f2", "g_table"):
        if name.startswith(g):
            return g
    return "b" if name.startswith("b_") else "M"


# --------------------------------------------------------------------------- calibration


@dataclass(frozen=True)
class CalibrationDesign:
    """The simulated calibration experiment: table attitudes, timing and truth."""

    euler: np.ndarray  # (K, 3) rad, table attitudes of the steps
    schedule: StepSchedule
    g: float  # gravity magnitude [m/s²]
    g_table: np.ndarray  # (3,) gravity in table coordinates
    F_inv: np.ndarray
    b_prime: np.ndarray
    f2: np.ndarray
    noise_std: float

    @property
    def R(self) -> np.ndarray:
        """Body-to-table rotation of every step, (K, 3, 3)."""
        return euler_to_rotation(self.euler)

    def truth(self, quadratic: bool = True) -> np.ndarray:
        """True parameter vector (order of :data:`PARAMETERS`); ``f2 = 0`` if not ``quadratic``."""
        return pack(self.F_inv, self.b_prime, self.f2 if quadratic else np.zeros(3), self.g_table)

    def window_means(self, quadratic: bool = True) -> np.ndarray:
        """Noise-free accelerometer output in every window, (K, 3)."""
        a = specific_force_at_rest(self.R, self.g_table)
        return accelerometer_output(a, self.F_inv, self.b_prime, self.f2 if quadratic else np.zeros(3))


def calibration_design(roll_deg, pitch_deg, yaw_deg, mounting_offset_deg, g, F_inv, b_prime, f2, noise_std,
                       **schedule) -> CalibrationDesign:
    """Assemble a :class:`CalibrationDesign` (see :func:`~accelcal_repro.batista2011.trajectory.stepped_attitudes`)."""
    eul = stepped_attitudes(roll_deg, pitch_deg, yaw_deg)
    return CalibrationDesign(
        euler=eul, schedule=StepSchedule(n_steps=len(eul), **schedule), g=float(g),
        g_table=gravity_in_table(np.deg2rad(np.asarray(mounting_offset_deg, float)), g),
        F_inv=np.asarray(F_inv, float), b_prime=np.asarray(b_prime, float), f2=np.asarray(f2, float),
        noise_std=float(noise_std))


DATASETS = {"quadratic": True, "linear": False}  # data with the paper's F2, and with F2 = 0
METHODS = ("batista2011", "batista2011_linear", "full_lls")


def calibration_montecarlo(design: CalibrationDesign, rngs, tol: float = 1e-10, max_iter: int = 50,
                           chunk: int = 50, run_ids=None) -> pd.DataFrame:
    """Monte Carlo of Table I against the truth, with two baselines on the same noise.

    Each run draws white noise of std ``design.noise_std`` on every sample of every
    static window; the same noise is added to two data sets: ``quadratic`` (the paper's
    ``F2``) and ``linear`` (``F2 = 0``).  On each, three estimators:

    * ``batista2011``: Table I (steps 1-5), 18 parameters;
    * ``batista2011_linear``: steps 1-2 only (no quadratic term; ``f2`` reported 0);
    * ``full_lls``: Burkhard et al. (2024) full LLS on the window means: it ignores
      the quadratic term and the known rotations, and estimates only the bias
      ``b = F b'`` and the lower-triangular ``M`` with ``M Mᵀ = F Fᵀ``.

    ``b`` and ``M`` are also derived from the Table I estimates, so that all methods
    are compared on the same quantities.

    Parameters
    ----------
    design : CalibrationDesign
    rngs : sequence of numpy.random.Generator
        One per run (:func:`run_streams`); run ``i`` draws its noise from ``rngs[i]`` only.
    tol, max_iter : float, int
        Stopping rule of Table I's Gauss-Newton steps.
    chunk : int
        Runs estimated together (vectorised); does not change any number.
    run_ids : array-like of int, optional
        The runs' numbers in the ``run`` column (default ``0 .. len(rngs) - 1``).

    Returns
    -------
    pandas.DataFrame
        Columns ``run, data, method, parameter, group, estimate, truth, error,
        converged, iterations``.
    """
    R = design.R
    K, n = len(R), design.schedule.samples_per_window
    mus = {d: design.window_means(q) for d, q in DATASETS.items()}
    truths = {d: design.truth(q) for d, q in DATASETS.items()}
    dtruth = {d: derived_quantities(v) for d, v in truths.items()}
    runs = len(rngs)
    all_ids = np.arange(runs) if run_ids is None else np.asarray(run_ids, int)
    if len(all_ids) != runs:
        raise ValueError(f"{len(all_ids)} run ids for {runs} random streams")
    frames = []
    for start in range(0, runs, chunk):
        T = min(chunk, runs - start)
        noise = design.noise_std * np.stack([g.standard_normal((K, n, 3)) for g in rngs[start:start + T]])
        run_ids = all_ids[start:start + T]
        for data, quad in DATASETS.items():
            stats = WindowStatistics.from_samples(mus[data][None, :, None, :] + noise)
            for method, quadratic in (("batista2011", True), ("batista2011_linear", False)):
                r = calibrate_batch(stats, R, design.g, tol=tol, max_iter=max_iter, quadratic=quadratic)
                est = r.vectors()
                der = np.array([derived_quantities(v) for v in est])
                keep = _estimated(method)
                frames.append(_rows(run_ids, data, method, tuple(np.array(PARAMETERS + DERIVED)[keep]),
                                    np.hstack([est, der])[:, keep],
                                    np.concatenate([truths[data], dtruth[data]])[keep], r.converged, r.iterations))
            lls = full_lls_batch(stats.means, design.g)
            der = np.hstack([lls.bias, lls.M[:, _LOWER[0], _LOWER[1]]])
            frames.append(_rows(run_ids, data, "full_lls", DERIVED, der, dtruth[data], lls.valid,
                                np.zeros(T, int)))
    return pd.concat(frames, ignore_index=True)


def _estimated(method: str) -> np.ndarray:
    """Indices (into parameters + derived) a Table I variant estimates: no ``f2`` for the linear one."""
    idx = np.arange(27)
    return idx[(idx < 12) | (idx >= 15)] if method == "batista2011_linear" else idx


def _rows(run_ids, data, method, names, est, truth, converged, iterations) -> pd.DataFrame:
    T, P = est.shape
    return pd.DataFrame({
        "run": np.repeat(run_ids, P),
        "data": data,
        "method": method,
        "parameter": np.tile(np.array(names, dtype=object), T),
        "group": np.tile(np.array([_group(s) for s in names], dtype=object), T),
        "estimate": est.ravel(),
        "truth": np.tile(truth, T),
        "error": (est - truth).ravel(),
        "converged": np.repeat(np.asarray(converged, bool), P),
        "iterations": np.repeat(np.asarray(iterations, int), P),
    })


def asymptotic_bias(design: CalibrationDesign, quadratic_data: bool = True, quadratic_method: bool = True,
                    tol: float = 1e-14, max_iter: int = 100) -> np.ndarray:
    """Deterministic O(σ²) bias of Table I: the estimate from the *expected* window statistics.

    The noisy ``a_m`` enters ``X`` (errors in variables), so ``E[XᵀX] = X₀ᵀX₀ + N σ² diag(I₉, 0)``
    and the null vector of ``XᵀX`` is pulled away from the truth by a term that does
    not average out over Monte Carlo runs.  This returns estimate − truth computed from
    ``E[Σ a_m] = n μ_k`` and ``E[Σ a_m a_mᵀ] = n (μ_k μ_kᵀ + σ² I)``: the limit of the
    Monte Carlo mean error when the number of windows grows (27 values: parameters then
    derived quantities).
    """
    mu = design.window_means(quadratic_data)
    n = float(design.schedule.samples_per_window)
    stats = WindowStatistics(np.full(len(mu), n), (n * mu)[None],
                             (n * (np.einsum("ki,kj->kij", mu, mu) + design.noise_std**2 * np.eye(3)))[None])
    est = calibrate_batch(stats, design.R, design.g, tol=tol, max_iter=max_iter,
                          quadratic=quadratic_method).vectors()[0]
    truth = design.truth(quadratic_data)
    return np.concatenate([est - truth, derived_quantities(est) - derived_quantities(truth)])


def calibration_bounds(design: CalibrationDesign) -> pd.DataFrame:
    """CRLB of each method's model and the asymptotic bias, per data set, method and parameter.

    ``crlb_std`` is the bound of the model each method fits: for ``batista2011`` the
    constrained CRLB of the 18-parameter model with the known table rotations
    (:func:`accelcal.batista.crlb.calibration_crlb`), for ``batista2011_linear`` the
    same with ``f2`` known, and for ``full_lls`` the bound of the model without ``F2``
    and with unknown pose directions (:func:`accelcal.crlb` on the window means, ``b``
    and ``M`` converted from its ``(b, s, θ)``).  ``asymptotic_bias`` from
    :func:`asymptotic_bias` (NaN for the LLS).

    Returns
    -------
    pandas.DataFrame
        Columns ``data, method, parameter, group, truth, crlb_std, asymptotic_bias``.
    """
    frames = []
    n = design.schedule.samples_per_window
    names = PARAMETERS + DERIVED
    F = np.linalg.inv(design.F_inv)
    M = np.linalg.cholesky(F @ F.T)
    # the LLS model z = M x + b with x = M⁻¹ F a (an orthonormal change of frame), |x| = g
    u = specific_force_at_rest(design.R, design.g_table) @ (np.linalg.inv(M) @ F).T / design.g
    lls = lls_crlb(u, design.g, design.noise_std / np.sqrt(n), M)
    s, th = params_from_m(M)
    D = np.zeros((9, 9))
    D[:3, :3] = np.eye(3)
    D[3:, 3:] = np.moveaxis(dM_dparams(s, th), 0, -1)[_LOWER]  # ∂M_lower/∂(s, θ)
    lls_std = np.sqrt(np.diag(D @ lls.cov @ D.T))
    for data, quad in DATASETS.items():
        truth = design.truth(quad)
        tvals = np.concatenate([truth, derived_quantities(truth)])
        for method in METHODS:
            if method == "full_lls":
                sel, std, ab = slice(18, 27), np.concatenate([np.full(18, np.nan), lls_std]), np.full(27, np.nan)
            else:
                bound = calibration_crlb(truth[:9].reshape(3, 3), truth[9:12], truth[12:15], truth[15:18],
                                         design.R, n, design.noise_std, estimate_f2=method == "batista2011")
                sel, std = slice(0, 27), np.concatenate([bound.std, bound.derived_std])
                ab = asymptotic_bias(design, quad, method == "batista2011")
            sel = np.arange(27)[sel] if method == "full_lls" else _estimated(method)
            frames.append(pd.DataFrame({
                "data": data, "method": method, "parameter": np.array(names)[sel],
                "group": [_group(names[i]) for i in sel],
                "truth": tvals[sel], "crlb_std": std[sel], "asymptotic_bias": ab[sel],
            }))
    return pd.concat(frames, ignore_index=True)


def calibration_summary(errors: pd.DataFrame, bounds: pd.DataFrame) -> pd.DataFrame:
    """Error statistics over runs per data set, method and parameter, beside the bounds.

    Columns: ``data, method, parameter, group, n_runs, n_converged, mean_error,
    std_error, rms_error, se_mean, t_mean`` (mean / its standard error),
    ``crlb_std, std_over_crlb, crlb_std_unknown_attitude, asymptotic_bias, truth``.
    Non-converged (or, for the LLS, invalid) runs are left out of the statistics.
    """
    ok = errors[errors["converged"]]
    g = ok.groupby(["data", "method", "parameter"], sort=False)["error"]
    s = pd.DataFrame({"n_runs": g.size(), "mean_error": g.mean(), "std_error": g.std(ddof=1),
                      "rms_error": g.apply(lambda e: float(np.sqrt(np.mean(e**2))))}).reset_index()
    conv = errors.groupby(["data", "method", "parameter"], sort=False)["converged"].sum().rename("n_converged")
    s = s.merge(conv.reset_index(), on=["data", "method", "parameter"])
    s["se_mean"] = s["std_error"] / np.sqrt(s["n_runs"])
    s["t_mean"] = s["mean_error"] / s["se_mean"]
    s = s.merge(bounds, on=["data", "method", "parameter"], how="left")
    s["std_over_crlb"] = s["std_error"] / s["crlb_std"]
    cols = ["data", "method", "parameter", "group", "truth", "n_runs", "n_converged", "mean_error", "std_error",
            "rms_error", "se_mean", "t_mean", "crlb_std", "std_over_crlb", "asymptotic_bias"]
    return s[cols]


def lls_comparison(errors: pd.DataFrame) -> pd.DataFrame:
    """RMS over runs of the error norm of ``b`` and of ``M`` (Frobenius), per data set and method.

    The quantities every method estimates: Table I derives them from ``F⁻¹`` and
    ``b'``, the full LLS estimates them directly.  Columns ``data, method, quantity,
    rms_norm, mean_norm_of_mean`` (the latter: norm of the mean error vector, i.e. the
    systematic part).
    """
    rows = []
    d = errors[errors["group"].isin(["b", "M"]) & errors["converged"]]
    for (data, method, grp), sub in d.groupby(["data", "method", "group"], sort=False):
        wide = sub.pivot(index="run", columns="parameter", values="error")
        rows.append({"data": data, "method": method, "quantity": grp,
                     "rms_norm": float(np.sqrt(np.mean(np.sum(wide.to_numpy() ** 2, axis=1)))),
                     "mean_norm_of_mean": float(np.linalg.norm(wide.mean(axis=0).to_numpy())),
                     "n_runs": len(wide)})
    return pd.DataFrame(rows)


# ----------------------------------------------------------------------------- filter


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


def _mv(M: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Batched 3x3 matrix-vector product, layout ``M`` (3, 3, T), ``v`` (3, T)."""
    return (M * v[None]).sum(axis=1)


def shared_gain_filter(dt: float, a_m, omega_m, y, x0, gains, record, sub_block: int = 25) -> np.ndarray:
    """The Kalman filter of Sec. IV on many runs with a precomputed gain sequence.

    Each run propagates its state with its own gyro readings (exact ``Φ`` in closed
    form, first-order hold of ``a_m``, as :func:`accelcal.batista.filter.kalman_filter`)
    and updates with ``gains[k]`` (from :func:`~accelcal.batista.filter.covariance_sequence`).

    Parameters
    ----------
    dt : float
    a_m, omega_m, y : array_like, shape (T, n, 3)
    x0 : array_like, shape (T, 9)
    gains : array_like, shape (n, 9, 3)
    record : array_like of int
        Sample indices to return (sorted).
    sub_block : int
        Samples processed per vectorised chunk (small chunks stay in cache).

    Returns
    -------
    numpy.ndarray, shape (T, len(record), 9)
    """
    a_m, omega_m, y = (np.asarray(v, float) for v in (a_m, omega_m, y))
    st = _FilterState(np.asarray(x0, float), a_m[:, 0], omega_m[:, 0], np.asarray(record), dt)
    gains = np.asarray(gains, float)
    for k0 in range(1, a_m.shape[1], sub_block):
        sl = slice(k0, k0 + sub_block)
        st.run_block(a_m[:, sl], omega_m[:, sl], y[:, sl], gains, k0)
    return st.out


def _blocks_bkt(w: np.ndarray, dt: float):
    """:func:`~accelcal.batista.filter.rotation_blocks` (``J1`` divided by ``dt``) for
    ``w`` of layout (B, 3, T), returned in layout (B, 3, 3, T), by elementwise arithmetic
    (``S(w)² = w wᵀ - |w|² I``), which is much faster than batched 3x3 products."""
    w = w * dt
    th2 = np.einsum("bit,bit->bt", w, w)
    a, b, c, d, e = rotation_coefficients(np.sqrt(th2))
    K = np.zeros(w.shape[:1] + (3, 3) + w.shape[2:])
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    WW = w[:, :, None] * w[:, None, :]
    out = []
    for c0, c1, c2, scale in ((1.0, a, b, 1.0), (1.0, b, c, dt), (0.5, d, e, dt)):
        M = c2[:, None, None] * WW - c1[:, None, None] * K
        diag = c0 - c2 * th2
        for i in range(3):
            M[:, i, i] += diag
        out.append(M * scale if scale != 1.0 else M)
    return tuple(out)


def _compiled_block():
    """The compiled block loop when the filter kernels run compiled (:mod:`accelcal.kernels`), else None."""
    if compiled("batista._filter_kernels") is None:
        return None
    from . import _shared_gain_kernels

    return _shared_gain_kernels


class _FilterState:
    """Running state of :func:`shared_gain_filter` fed block by block (memory stays bounded).

    With numba the block runs as the compiled kernel
    :func:`accelcal_repro.batista2011._shared_gain_kernels.shared_gain_block` (state ``x`` kept as (T, 9));
    the numpy loop below is the reference (state as (9, T))."""

    def __init__(self, x0, a0, w0, record, dt):
        self.kernels = _compiled_block()
        x0 = np.asarray(x0, float)
        self.x = np.array(x0) if self.kernels is not None else np.ascontiguousarray(x0.T)
        self.a_prev = np.array(a0, float)
        self.w_prev = np.array(w0, float)
        self.record = np.asarray(record, int)
        self.recorded = np.zeros(int(self.record.max(initial=-1)) + 1, bool)  # sample index -> recorded?
        self.recorded[self.record] = True
        self.dt = dt
        self.out = np.empty((len(x0), len(self.record), 9))
        self.j = 0
        self._store(0)

    def _store(self, k):
        while self.j < len(self.record) and self.record[self.j] == k:
            self.out[:, self.j] = self.x if self.kernels is not None else self.x.T
            self.j += 1

    def run_block(self, a, w, y, gains, k0):
        """Samples ``k0 .. k0 + B - 1``: ``a``, ``w``, ``y`` of shape (T, B, 3)."""
        if self.kernels is not None:
            B = a.shape[1]
            store = np.zeros(B, bool)
            part = self.recorded[k0:k0 + B]
            store[:len(part)] = part
            c = np.ascontiguousarray
            self.kernels.shared_gain_block(self.dt, self.x, self.a_prev, self.w_prev, c(a, dtype=float),
                                           c(w, dtype=float), c(y, dtype=float), c(gains[k0:k0 + B]), store,
                                           self.out, self.j)
            self.j += int(store.sum())
            return
        dt = self.dt
        wT = np.moveaxis(w, 0, -1)  # (B, 3, T)
        wbar = 0.5 * (np.concatenate([self.w_prev.T[None], wT[:-1]], axis=0) + wT)
        E, J0, J1 = _blocks_bkt(wbar, dt)  # (B, 3, 3, T)
        aT = np.ascontiguousarray(np.moveaxis(a, 0, -1))  # (B, 3, T)
        yT = np.ascontiguousarray(np.moveaxis(y, 0, -1))
        a0 = self.a_prev.T
        x = self.x
        for i in range(a.shape[1]):
            v, g, b = x[:3], x[3:6], x[6:]
            a1 = aT[i]
            # x⁻ = Φ x + G0 a_k + G1 a_{k+1}, with -J0 b + (J1/dt) a_k + (J0 - J1/dt) a_{k+1}
            v_new = _mv(E[i], v + dt * g) + _mv(J0[i], a1 - b) + _mv(J1[i], a0 - a1)
            g_new = _mv(E[i], g)
            innov = yT[i] - v_new
            x = np.concatenate([v_new, g_new, b]) + gains[k0 + i] @ innov
            a0 = a1
            self.x = x
            self._store(k0 + i)
        self.a_prev = a[:, -1]
        self.w_prev = w[:, -1]


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
    err = st.out - sc.x_true()[both][None]  # (T, n_both, 9)
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


# ------------------------------------------------------------------------ observability


def observability_table(mc: FilterMonteCarlo, axis_body, case: str) -> pd.DataFrame:
    """Errors of ``g`` and ``b`` along the body axis ``n`` and across it, over runs.

    Columns ``case, t, component`` (``g_axial``, ``b_axial``, ``g_perp``, ``b_perp``),
    ``mean_error`` (signed for axial, mean norm for perp), ``rms_error``,
    ``filter_sigma`` (``sqrt(nᵀ P n)`` for axial, ``sqrt(tr P - nᵀ P n)`` for perp).
    """
    nvec = np.asarray(axis_body, float)
    nvec = nvec / np.linalg.norm(nvec)
    runs = mc.runs
    times = np.sort(runs["t"].unique())
    rows = []
    for name, blk in (("g", slice(3, 6)), ("b", slice(6, 9))):
        cols = [f"e_{name}_{a}" for a in "xyz"]
        E = runs[cols].to_numpy().reshape(-1, len(times), 3)  # (runs, times, 3)
        ax = E @ nvec
        perp = np.linalg.norm(E - ax[..., None] * nvec, axis=-1)
        Pb = mc.P[:, blk, blk]
        s_ax = np.sqrt(np.einsum("i,kij,j->k", nvec, Pb, nvec))
        s_perp = np.sqrt(np.clip(np.einsum("kii->k", Pb) - s_ax**2, 0, None))
        for comp, val, sig in ((f"{name}_axial", ax, s_ax), (f"{name}_perp", perp, s_perp)):
            rows.append(pd.DataFrame({"case": case, "t": times, "component": comp, "mean_error": val.mean(0),
                                      "rms_error": np.sqrt((val**2).mean(0)), "filter_sigma": sig}))
    return pd.concat(rows, ignore_index=True)


def gramian_table(t, omega, axis_body, case: str) -> pd.DataFrame:
    """Smallest eigenvalues of the observability Gramian of eq. (7) and the null direction.

    Columns ``case, window_s, eig_min, eig_max, eig_ratio, null_alignment`` with
    ``null_alignment = |v_min · (0, n, n)/√2|`` (1 when the unobservable direction is
    "equal shifts of g and b along the rotation axis").
    """
    W = observability_gramian(t, omega)
    ev, V = np.linalg.eigh(W)
    nvec = np.asarray(axis_body, float)
    nvec = nvec / np.linalg.norm(nvec)
    null = np.concatenate([np.zeros(3), nvec, nvec]) / np.sqrt(2)
    return pd.DataFrame([{"case": case, "window_s": float(t[-1] - t[0]), "eig_min": ev[0], "eig_max": ev[-1],
                          "eig_ratio": ev[0] / ev[-1], "null_alignment": float(abs(V[:, 0] @ null))}])


__all__ = [
    "DATASETS",
    "METHODS",
    "CalibrationDesign",
    "FilterMonteCarlo",
    "FilterScenario",
    "asymptotic_bias",
    "calibration_bounds",
    "calibration_design",
    "calibration_montecarlo",
    "calibration_summary",
    "filter_cost",
    "filter_error_budget",
    "filter_example",
    "filter_montecarlo",
    "filter_scenario",
    "filter_summary",
    "gramian_table",
    "initial_estimate",
    "lls_comparison",
    "merge_filter_moments",
    "observability_table",
    "run_streams",
    "shared_gain_filter",
    "stream",
]
