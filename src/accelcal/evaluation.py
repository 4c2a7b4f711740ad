"""Evaluation without ground truth: noise-predicted residuals and χ², leave-one-pose-out
prediction, bootstrap over poses, agreement between estimators.

Real recordings come with no true bias or scale.  What can be checked is internal:

* **Residuals against the noise.**  A pose's residual ``r_i = ||M⁻¹(z_i - b)|| - g`` is,
  to first order, the noise of its mean projected on ``w_i = ∂r_i/∂z_i = x̂_iᵀ M⁻¹``, so
  the noise alone predicts ``σ_r,i² = Σ_k w_ik² σ_ik²`` from the pose-mean standard
  errors ``σ_ik`` of the static detection.  ``χ² = Σ r_i² / σ_r,i²`` has ``n - q``
  degrees of freedom if the model and the noise level are right; ``sqrt(χ²/(n - q))``
  (the *excess*) says how many times the residuals exceed what the noise explains.
* **Leave-one-pose-out (LOPO).**  Fit without pose i, predict its magnitude:
  ``||M₋ᵢ⁻¹(z_i - b₋ᵢ)|| - g``.  The pose direction is unknown, so its magnitude is all a
  calibration can predict.  Needs ``n - 1`` poses to satisfy the estimator (10 for the
  full model, 4 for bias-only).
* **Bootstrap over poses.**  Resample the poses with replacement, refit.  A replicate
  with fewer distinct poses than the estimator needs, or on which it fails, is invalid;
  the percentile interval is reported only if at least ``min_valid_fraction`` of the
  replicates are valid, because dropping invalid ones conditions the bootstrap on the
  well-spread resamples and narrows the interval (with 10 poses and a 9-parameter model
  virtually none are valid: 10!/10¹⁰ ≈ 4e-4).  Otherwise the linearised standard error
  from the pose noise is used (:func:`noise_interval`).
* **Agreement.**  Differences of the same parameter between estimators, with a paired
  bootstrap interval (the same resampled poses for every estimator of a recording).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import distributions as dist
from .errors import AccelcalError
from .uncertainty import pose_residuals, residual_jacobian


def residual_sigma(z, mean_std, M, bias) -> np.ndarray:
    """Noise-predicted standard deviation of each pose residual.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Pose means (the unit the model was fitted in).
    mean_std : array_like, shape (n, 3)
        Standard error of each axis of each pose mean, same unit.
    M, bias : array_like
        The fitted model.

    Returns
    -------
    ndarray, shape (n,)
        ``σ_r,i`` in the unit of g (what the residuals are in).
    """
    w = -residual_jacobian(z, M, bias, "bias")  # ∂r/∂z = -∂r/∂b
    return np.sqrt(np.sum((w * np.asarray(mean_std, float)) ** 2, axis=1))


@dataclass(frozen=True)
class Chi2:
    """χ² of residuals against their noise prediction."""

    chi2: float
    dof: int
    p_value: float

    @property
    def reduced(self) -> float:
        return self.chi2 / self.dof if self.dof > 0 else float("nan")

    @property
    def excess(self) -> float:
        """``sqrt(χ²/dof)``: how many times the residuals exceed the noise (1 = explained)."""
        return float(np.sqrt(self.reduced))


def chi2_test(residuals, sigma, n_params: int) -> Chi2:
    """χ² statistic with ``n - n_params`` degrees of freedom and its upper-tail p-value."""
    r = np.asarray(residuals, float)
    s = np.asarray(sigma, float)
    c = float(np.sum((r / s) ** 2))
    dof = r.size - n_params
    p = dist.chi2_sf(c, dof)
    return Chi2(c, dof, p)


def lopo(fit, z, g: float, min_poses: int) -> tuple[np.ndarray, str]:
    """Leave-one-pose-out prediction errors.

    Parameters
    ----------
    fit : callable
        ``fit(z_subset) -> result`` with ``.M`` and ``.bias`` (g and noise bound in).
    z : array_like, shape (n, 3)
    g : float
    min_poses : int
        Fewest poses ``fit`` accepts.

    Returns
    -------
    errors : ndarray, shape (n,)
        ``||M₋ᵢ⁻¹(z_i - b₋ᵢ)|| - g``; NaN where the reduced fit failed or was impossible.
    note : str
        Empty, or why some or all errors are missing.
    """
    z = np.asarray(z, float)
    n = len(z)
    out = np.full(n, np.nan)
    if n - 1 < min_poses:
        return out, f"not possible: {n - 1} remaining poses < {min_poses} needed"
    failures = []
    for i in range(n):
        keep = np.arange(n) != i
        try:
            r = fit(z[keep])
        except AccelcalError as e:
            failures.append(f"pose {i}: {type(e).__name__}")
            continue
        out[i] = pose_residuals(z[i:i + 1], g, r.M, r.bias)[0]
    note = f"{len(failures)} of {n} reduced fits failed ({'; '.join(failures[:3])})" if failures else ""
    return out, note


def bootstrap_indices(n: int, n_boot: int, rng: np.random.Generator) -> np.ndarray:
    """``(n_boot, n)`` pose indices drawn with replacement (shared by the estimators of a recording)."""
    return rng.integers(0, n, size=(n_boot, n))


def bootstrap(fit, params, z, idx, min_poses: int, q: int) -> tuple[np.ndarray, np.ndarray]:
    """Refit on each resample ``z[idx[b]]``.

    Parameters
    ----------
    fit : callable
        ``fit(z_subset) -> result``.
    params : callable
        ``params(result) -> (q,)`` parameter vector.
    z : array_like, shape (n, 3)
    idx : ndarray of int, shape (B, n)
        Resampled indices (:func:`bootstrap_indices`).
    min_poses : int
        Fewest *distinct* poses a replicate needs to be attempted.
    q : int
        Length of the parameter vector.

    Returns
    -------
    samples : ndarray, shape (B, q)
        Parameter vectors; NaN rows for invalid replicates.
    valid : ndarray of bool, shape (B,)
    """
    z = np.asarray(z, float)
    samples = np.full((len(idx), q), np.nan)
    for b, ix in enumerate(idx):
        if np.unique(ix).size < min_poses:
            continue
        try:
            samples[b] = params(fit(z[ix]))
        except AccelcalError:
            continue
    return samples, np.all(np.isfinite(samples), axis=1)


def percentile_ci(samples, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval of each column over the finite rows."""
    a = (1 - level) / 2
    s = np.asarray(samples, float)
    s = s[np.all(np.isfinite(s), axis=1)]
    if len(s) == 0:
        nan = np.full(np.asarray(samples).shape[1], np.nan)
        return nan, nan
    return np.quantile(s, a, axis=0), np.quantile(s, 1 - a, axis=0)


def t_interval(value, se, dof: int, level: float) -> tuple[np.ndarray, np.ndarray]:
    """``value ± t_{(1+level)/2, dof} se``; NaN if ``dof <= 0``."""
    value = np.asarray(value, float)
    se = np.asarray(se, float)
    if dof <= 0:
        nan = np.full(value.shape, np.nan)
        return nan, nan
    k = dist.t_ppf(0.5 + level / 2, dof)
    return value - k * se, value + k * se


def noise_interval(value, se_noise, chi: Chi2, level: float) -> tuple[np.ndarray, np.ndarray]:
    """``value ± z_{(1+level)/2} · se_noise · max(1, excess)``: the fallback interval.

    Used where the bootstrap over poses is impossible (too few poses).  ``se_noise``
    (:func:`noise_standard_errors`) rests on the measured pose-mean standard errors,
    each from hundreds of samples, hence the normal quantile; where the residuals exceed
    the noise (``excess > 1``) it is inflated by the excess (the Particle Data Group's
    scale factor), so that the interval covers the misfit too.  The residual-scaled
    standard error is not used: with 1-3 degrees of freedom its σ̂ is itself a guess
    (the MPU-6050 full model has one, and its residuals happen to be ~50x below the noise).
    """
    k = dist.norm_ppf(0.5 + level / 2) * max(1.0, chi.excess if np.isfinite(chi.excess) else 1.0)  # normal quantile
    value = np.asarray(value, float)
    se = np.asarray(se_noise, float)
    return value - k * se, value + k * se


def noise_standard_errors(z, mean_std, M, bias, model: str) -> np.ndarray:
    """Standard errors the pose noise alone implies: ``sqrt(diag((Jᵀ W J)⁻¹))``, ``W = diag(1/σ_r²)``.

    Same parameter order and units as :func:`accelcal.uncertainty.standard_errors`
    (b, then s, then θ in radians).  They ignore model error: compare with the
    residual-scaled standard errors, which include it.
    """
    J = residual_jacobian(z, M, bias, model)
    s = residual_sigma(z, mean_std, M, bias)
    Jw = J / s[:, None]
    try:
        return np.sqrt(np.clip(np.diag(np.linalg.inv(Jw.T @ Jw)), 0, None))
    except np.linalg.LinAlgError:
        return np.full(J.shape[1], np.nan)


__all__ = [
    "Chi2",
    "bootstrap",
    "bootstrap_indices",
    "chi2_test",
    "lopo",
    "noise_interval",
    "noise_standard_errors",
    "percentile_ci",
    "residual_sigma",
    "t_interval",
]
