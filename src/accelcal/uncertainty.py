"""Residuals, standard errors and the Cramér–Rao bound of the static calibration models.

The measurement of pose i is ``z_i = M g u_i + b + e_i`` with ``e_i ~ N(0, Σ)``.
The unknown pose direction ``u_i`` (two angles) is a nuisance parameter: the Fisher
information on the calibration parameters ``p`` is what remains after it is
eliminated (Schur complement), i.e. only the component of ``∂z_i/∂p`` normal to the
ellipsoid ``{M g u + b}`` at ``z_i`` carries information::

    F = Σ_i J_iᵀ (Σ⁻¹ - Σ⁻¹ T_i (T_iᵀ Σ⁻¹ T_i)⁻¹ T_iᵀ Σ⁻¹) J_i,
    J_i = ∂z_i/∂p,  T_i = M g [t1_i, t2_i]  (tangent directions of u_i)

and ``CRLB = F⁻¹``.  Parameters are ``(b, s, θ)`` for the full model and ``b`` for
the bias-only model (with ``M = I``), ``g`` known.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import BIAS_PARAMETERS, FULL_PARAMETERS, dM_dparams, params_from_m


def pose_residuals(z, g, M, bias) -> np.ndarray:
    """``||M⁻¹(z_i - b)|| - g`` for every pose: the misfit every estimator reports."""
    x = np.linalg.solve(np.asarray(M, float), (np.asarray(z, float) - bias).T).T
    return np.linalg.norm(x, axis=1) - g


def residual_jacobian(z, M, bias, model: str) -> np.ndarray:
    """Jacobian of :func:`pose_residuals` w.r.t. ``(b, s, θ)`` (full) or ``b`` (bias)."""
    z = np.asarray(z, float)
    M = np.asarray(M, float)
    A = np.linalg.inv(M)
    x = (z - bias) @ A.T
    xhat = x / np.linalg.norm(x, axis=1, keepdims=True)
    w = xhat @ A  # (n, 3): d r_i / d z_i
    cols = [-w]
    if model == "full":
        s, th = params_from_m(M)
        dM = dM_dparams(s, th)  # (6, 3, 3)
        # x = M⁻¹(z - b)  =>  dx/dp = -M⁻¹ (dM/dp) x  =>  dr/dp = -x̂ᵀ M⁻¹ (dM/dp) x
        cols.append(-np.einsum("ni,kij,nj->nk", w, dM, x))
    return np.concatenate(cols, axis=1)


def standard_errors(z, g, M, bias, model: str) -> dict[str, np.ndarray]:
    """Linearised standard errors of the estimated parameters.

    ``cov = σ̂² (JᵀJ)⁻¹`` with ``σ̂² = RSS / (n - q)``: the residual of a pose is, to
    first order, the noise projected on the pose direction, so σ̂ estimates the per-axis
    noise of the pose means.  NaN when ``n == q`` (no degree of freedom left).
    """
    r = pose_residuals(z, g, M, bias)
    J = residual_jacobian(z, M, bias, model)
    n, q = J.shape
    sig2 = float(r @ r) / (n - q) if n > q else np.nan
    try:
        cov = sig2 * np.linalg.inv(J.T @ J)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        se = np.full(q, np.nan)
    out = {"bias": se[:3], "noise_std": np.array(np.sqrt(sig2))}
    if model == "full":
        out["scale_factors"] = se[3:6]
        out["nonorthogonality_deg"] = np.rad2deg(se[6:9])
    return out


@dataclass(frozen=True)
class CramerRaoBound:
    """Cramér–Rao bound on ``parameters`` for one pose set and noise level."""

    parameters: tuple[str, ...]
    cov: np.ndarray

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov))

    @property
    def bias_rms(self) -> float:
        """Bound on the RMS of the bias error norm, ``sqrt(E||b̂ - b||²)``."""
        return float(np.sqrt(np.trace(self.cov[:3, :3])))

    @property
    def scale_rms(self) -> float:
        return float(np.sqrt(np.trace(self.cov[3:6, 3:6]))) if len(self.parameters) > 3 else np.nan

    @property
    def nonorth_rms(self) -> float:
        return float(np.sqrt(np.trace(self.cov[6:9, 6:9]))) if len(self.parameters) > 3 else np.nan


def crlb(directions, g: float, noise_std, M=None, model: str = "full") -> CramerRaoBound:
    """Cramér–Rao bound for static calibration with unknown pose directions.

    Parameters
    ----------
    directions : array_like, shape (n, 3)
        True gravity directions of the poses (unit vectors, sensor frame).
    g : float
        Gravity magnitude (known).
    noise_std : float or array_like (3,)
        Standard deviation of the noise of each axis of the pose means.
    M : array_like (3, 3), optional
        True error matrix (identity if omitted; ignored for ``model='bias'``).
    model : {'full', 'bias'}

    Returns
    -------
    CramerRaoBound
    """
    u = np.asarray(directions, float)
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    M = np.eye(3) if (M is None or model == "bias") else np.asarray(M, float)
    Sinv = np.diag(1.0 / np.broadcast_to(np.asarray(noise_std, float) ** 2, (3,)))
    n = len(u)
    J = np.zeros((n, 3, 3 if model == "bias" else 9))
    J[:, :, :3] = np.eye(3)
    if model == "full":
        s, th = params_from_m(M)
        J[:, :, 3:] = g * np.einsum("kij,nj->nik", dM_dparams(s, th), u)
    T = g * np.einsum("ij,njk->nik", M, _tangents(u))  # (n, 3, 2)
    STi = np.einsum("ij,njk->nik", Sinv, T)
    Tinfo = np.einsum("nji,njk->nik", T, STi)  # (n, 2, 2)
    W = Sinv[None] - np.einsum("nij,njk,nlk->nil", STi, np.linalg.inv(Tinfo), STi)
    F = np.einsum("nji,njk,nkl->il", J, W, J)
    names = BIAS_PARAMETERS if model == "bias" else FULL_PARAMETERS
    return CramerRaoBound(parameters=names, cov=np.linalg.inv(F))


def _tangents(u: np.ndarray) -> np.ndarray:
    """Two orthonormal tangent vectors of the sphere at each ``u`` (n, 3) -> (n, 3, 2)."""
    helper = np.where(np.abs(u[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(u, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(u, t1)
    return np.stack([t1, t2], axis=2)


def crlb_mean(directions_batch, g, noise_std, M_batch=None, model="full") -> CramerRaoBound:
    """CRLB averaged over Monte Carlo trials (mean covariance over pose sets and truths).

    The RMS error over trials is bounded by the square root of the mean of the per-trial
    bounds, which is what Monte Carlo RMS errors are drawn against.
    """
    covs = []
    for i, u in enumerate(np.asarray(directions_batch)):
        Mi = None if M_batch is None else np.asarray(M_batch)[i]
        covs.append(crlb(u, g, noise_std, Mi, model).cov)
    names = BIAS_PARAMETERS if model == "bias" else FULL_PARAMETERS
    return CramerRaoBound(parameters=names, cov=np.mean(covs, axis=0))


__all__ = [
    "CramerRaoBound",
    "crlb",
    "crlb_mean",
    "pose_residuals",
    "residual_jacobian",
    "standard_errors",
]
