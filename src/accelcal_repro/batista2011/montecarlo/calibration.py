"""The calibration experiment of Batista et al. (2011), Sec. V-A: Table I against the truth
on simulated stepped-table data, its bounds (CRLB, asymptotic bias) and statistics over runs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from accelcal.lls_batch import full_lls_batch
from accelcal.model import dM_dparams, params_from_m
from accelcal.uncertainty import crlb as lls_crlb
from accelcal.batista.calibration import PARAMETERS, WindowStatistics, calibrate_batch
from accelcal.batista.crlb import DERIVED, calibration_crlb, derived_quantities, pack
from accelcal.batista.model import accelerometer_output, euler_to_rotation, gravity_in_table, specific_force_at_rest
from ..trajectory import StepSchedule, stepped_attitudes

_LOWER = ([0, 1, 1, 2, 2, 2], [0, 0, 1, 0, 1, 2])

def _group(name: str) -> str:
    for g in ("F_inv", "b_prime", "f2", "g_table"):
        if name.startswith(g):
            return g
    return "b" if name.startswith("b_") else "M"


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
        for data in DATASETS:
            stats = WindowStatistics.from_samples(mus[data][None, :, None, :] + noise)
            frames += _dataset_rows(design, stats, data, truths[data], dtruth[data], run_ids, tol, max_iter)
    return pd.concat(frames, ignore_index=True)


def _dataset_rows(design: CalibrationDesign, stats, data: str, truth, dtruth, run_ids, tol: float,
                  max_iter: int) -> list[pd.DataFrame]:
    """The three estimators' rows of one chunk of runs on one data set (``stats``: its windows)."""
    frames = []
    for method, quadratic in (("batista2011", True), ("batista2011_linear", False)):
        r = calibrate_batch(stats, design.R, design.g, tol=tol, max_iter=max_iter, quadratic=quadratic)
        est = r.vectors()
        der = np.array([derived_quantities(v) for v in est])
        keep = _estimated(method)
        frames.append(_rows(run_ids, data, method, tuple(np.array(PARAMETERS + DERIVED)[keep]),
                            np.hstack([est, der])[:, keep], np.concatenate([truth, dtruth])[keep], r.converged,
                            r.iterations))
    lls = full_lls_batch(stats.means, design.g)
    der = np.hstack([lls.bias, lls.M[:, _LOWER[0], _LOWER[1]]])
    frames.append(_rows(run_ids, data, "full_lls", DERIVED, der, dtruth, lls.valid, np.zeros(len(run_ids), int)))
    return frames


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


__all__ = ["DATASETS", "METHODS", "CalibrationDesign", "asymptotic_bias", "calibration_bounds", "calibration_design",
           "calibration_montecarlo", "calibration_summary", "lls_comparison"]
