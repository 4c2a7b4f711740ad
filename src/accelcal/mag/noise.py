"""What the ellipsoid's residuals say about the noise: an autoregressive model of them.

The rests measure the magnetometer's own noise, but the residuals of an ellipsoid over a
whole session are far from independent (SNU good1-3: lag-1 autocorrelation 0.96-0.98,
still 0.5-0.8 at lag 50; CK-Explorer 0.71; QMC5883L 0.10): a field that differs slightly
from place to place, a low-passed sensor, a misfit that changes slowly with the
orientation.  Treating those samples as independent makes the standard errors 9-49x too
small between sessions.  An AR(p) model of the residuals (Yule-Walker, order by AIC up to
:data:`MAX_ORDER`) is the noise model that includes what they show: its whitening filter
turns residuals and Jacobian columns into (nearly) independent innovations, for the
parameters' covariance (:func:`ar_covariance`) and for the loop's nested tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Highest autoregressive order tried.
MAX_ORDER = 8


@dataclass(frozen=True)
class ARNoise:
    """``e_t = Σ_k a_k e_{t-k} + u_t`` with white innovations ``u`` of variance ``innovation_var``."""

    a: np.ndarray
    innovation_var: float
    variance: float
    lag1: float = 0.0  #: the residuals' lag-1 autocorrelation

    @property
    def order(self) -> int:
        return int(self.a.size)

    def whiten(self, x) -> np.ndarray:
        """The innovations of ``x`` (rows in time order; the first ``order`` rows dropped)."""
        x = np.asarray(x, float)
        p, n = self.order, len(x)
        out = x[p:].copy()
        for k in range(1, p + 1):
            out -= self.a[k - 1] * x[p - k:n - k]
        return out

    def to_dict(self) -> dict:
        return {"order": self.order, "coefficients": self.a.tolist(), "lag1": self.lag1,
                "innovation_share": self.innovation_var / max(self.variance, 1e-300)}


def _acov(x, p) -> np.ndarray:
    x = x - x.mean()
    n = len(x)
    return np.array([x[k:] @ x[:n - k] / n for k in range(p + 1)])


def fit_ar(residuals, max_order: int = MAX_ORDER) -> ARNoise:
    """AR(p) of a residual series (Yule-Walker; the order of least AIC, 0 = white)."""
    r = np.asarray(residuals, float)
    n = len(r)
    c = _acov(r, max(max_order, 1))
    best = (n * np.log(max(c[0], 1e-300)), np.zeros(0), c[0])
    for p in range(1, min(max_order, n // 10) + 1):
        T = np.array([[c[abs(i - j)] for j in range(p)] for i in range(p)])
        try:
            a = np.linalg.solve(T, c[1:p + 1])
        except np.linalg.LinAlgError:
            break
        s2 = float(c[0] - a @ c[1:p + 1])
        if not s2 > 0:
            break
        aic = n * np.log(s2) + 2 * p
        if aic < best[0]:
            best = (aic, a, s2)
    return ARNoise(a=best[1], innovation_var=float(best[2]), variance=float(c[0]), lag1=float(c[1] / max(c[0], 1e-300)))


def ar_covariance(J, r, noise: ARNoise | None = None) -> tuple[np.ndarray, ARNoise]:
    """Covariance of a least-squares estimate with residuals ``r`` and Jacobian ``J``
    (in any common unit) under AR noise fitted to ``r``: the generalised least-squares
    bound ``(J̃ᵀJ̃)⁻¹ s²`` with ``J̃`` the whitened Jacobian and ``s²`` the innovations'
    variance (with AR(0) the independent-sample covariance ``(JᵀJ)⁻¹ σ²``)."""
    noise = fit_ar(r) if noise is None else noise
    Jw = noise.whiten(J)
    cov = np.linalg.pinv(Jw.T @ Jw) * noise.innovation_var
    return cov, noise


def correlation_length(r) -> int:
    """The first lag at which the residuals' autocorrelation falls below 1/e (samples)."""
    x = np.asarray(r, float) - np.mean(r)
    n = len(x)
    f = np.fft.rfft(x, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[:n]
    below = np.flatnonzero(acf <= acf[0] / np.e)
    return int(below[0]) if below.size else n


def block_covariance(J, r) -> tuple[np.ndarray | None, dict]:
    """Covariance of a least-squares estimate whose residuals ``r`` are correlated over long
    stretches: the jackknife over blocks of samples (the cluster-robust sandwich's CR3 form),
    the blocks :data:`BLOCK_LENGTHS` correlation
    lengths long (at least :data:`MIN_BLOCKS`, at most :data:`MAX_BLOCKS` of them).

    It holds whatever the residuals' correlation (an AR model of a few lags cannot describe a
    misfit that changes with the orientation over hundreds of samples, SNU's), and it costs
    what a few blocks cost: the variance of a variance from ``K`` blocks (``K - 1`` dof)."""
    J, r = np.asarray(J, float), np.asarray(r, float)
    n = len(r)
    L = correlation_length(r)
    k = int(np.clip(n // max(BLOCK_LENGTHS * L, 1), MIN_BLOCKS, MAX_BLOCKS))
    if n < 2 * k * J.shape[1]:
        return None, {}
    edges = np.linspace(0, n, k + 1).astype(int)
    JJ = J.T @ J
    # the jackknife over blocks (each left out in turn, one Gauss-Newton step): the plain
    # sandwich's fitted residuals are pulled towards each block's own data and, with a dozen
    # blocks for nine parameters, it came out 35 % low in a Monte Carlo of correlated noise
    # (pinv: a column that lives inside one block, a disturbance's, is undetermined without it)
    d = np.array([np.linalg.pinv(JJ - J[a:b].T @ J[a:b]) @ (J[a:b].T @ r[a:b]) for a, b in zip(edges[:-1], edges[1:])])
    d -= d.mean(axis=0)
    cov = d.T @ d * (k - 1) / k
    return cov, {"blocks": k, "correlation_length": L}


#: Blocks of the sandwich: this many correlation lengths long, between MIN_BLOCKS and MAX_BLOCKS of them.
BLOCK_LENGTHS, MIN_BLOCKS, MAX_BLOCKS = 4, 12, 60

__all__ = ["ARNoise", "BLOCK_LENGTHS", "MAX_BLOCKS", "MAX_ORDER", "MIN_BLOCKS", "ar_covariance", "block_covariance",
           "correlation_length", "fit_ar"]
