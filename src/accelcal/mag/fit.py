"""Ellipsoid fits of field samples: the closed form (Li & Griffiths 2004, as Magneto 1.2)
and its maximum-likelihood refinement, with standard errors and the Cramér–Rao bound.

The samples are ``m_i = b + A⁻¹ h_i + e_i`` with |h_i| = 1 and ``e_i`` zero-mean noise of
covariance ``Σ`` (per axis, measured at the rests).  Every direction ``h_i`` is a nuisance
parameter; the first-order likelihood of the nine ellipsoid parameters is then the sum of
squared *Sampson* distances ``f_i / sqrt(∇f_iᵀ Σ ∇f_i)`` with ``f_i = |A (m_i - b)| - 1``
(the orthogonal distance to the ellipsoid weighted by the noise across it).  Its Fisher
information ``Jᵀ J`` at the true parameters is the bound; at the estimate it gives the
standard errors.  The mean of ``|h + e|`` exceeds 1 by half the tangential noise variance,
which would shrink ``A`` by ~σ²: the residual subtracts it when Σ is known (as ALS removes
the LLS bias for the accelerometer).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import distributions as dist  # scipy.stats would cost ~1 s at import
from .errors import MagDegenerateError, MagFitError, MagInputError
from .model import sym_from_vec, vec_from_sym
from .noise import block_covariance

#: Fewest samples: nine unknowns and one more so that a residual checks the fit.
MIN_SAMPLES = 10


@dataclass(frozen=True)
class FieldSamples:
    """The magnetometer's data kind: field samples and the noise measured at the rests.

    Attributes
    ----------
    m : ndarray (n, 3)
        Raw field samples (any unit: the fit is in it).
    noise_cov : ndarray (3, 3) or None
        Covariance of one sample's noise [raw unit²], measured at the rests; None: unknown
        (then estimated from the residual, and no χ² check is possible).
    noise_source : str
        Where ``noise_cov`` came from (a trust line quotes it).
    n_independent : float
        Effective number of independent samples (autocorrelated samples count less); the
        covariance of the estimate is inflated by ``n / n_independent``.
    """

    m: np.ndarray
    noise_cov: np.ndarray | None = None
    noise_source: str = "unknown"
    n_independent: float | None = None

    def __post_init__(self):
        m = np.array(self.m, dtype=float)
        if m.ndim != 2 or m.shape[1] != 3:
            raise MagInputError(f"field samples must be (n, 3), got {m.shape}")
        if not np.all(np.isfinite(m)):
            raise MagInputError("field samples contain NaN or infinite values: drop those rows")
        if m.shape[0] < MIN_SAMPLES:
            raise MagInputError(f"{m.shape[0]} field samples; an ellipsoid needs at least {MIN_SAMPLES}")
        object.__setattr__(self, "m", m)
        if self.noise_cov is not None:
            object.__setattr__(self, "noise_cov", np.array(self.noise_cov, dtype=float).reshape(3, 3))

    @property
    def n(self) -> int:
        return self.m.shape[0]


@dataclass(frozen=True)
class EllipsoidFit:
    """An ellipsoid ``|A (m - b)| = 1`` fitted to field samples.

    ``cov`` is the covariance of ``theta = [b, A_xx, A_xy, A_xz, A_yy, A_yz, A_zz]``
    (:data:`accelcal.mag.model.PARAMETERS`): the Cramér–Rao bound at the estimate for the
    measured noise, times χ²/dof when the χ² test rejects that noise (p < 0.01); with the
    noise unknown, scaled by the residual (and ``chi2`` is None).
    """

    A: np.ndarray
    b: np.ndarray
    method: str
    cov: np.ndarray | None = None
    chi2: float | None = None
    dof: int = 0
    residual_rms: float = float("nan")
    singular_values: np.ndarray | None = None
    iterations: int = 0
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def n_parameters(self) -> int:
        """Free parameters: 4 for the sphere (hard iron and one scale), else 9."""
        return 4 if self.method == "hard_iron" else 9

    @property
    def theta(self) -> np.ndarray:
        return np.concatenate([self.b, vec_from_sym(self.A)])

    @property
    def se(self) -> np.ndarray | None:
        return None if self.cov is None else np.sqrt(np.diag(self.cov))


def _sqrtm_spd(M) -> np.ndarray:
    w, V = np.linalg.eigh(M)
    return (V * np.sqrt(w)) @ V.T


def li_griffiths(m) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form ellipsoid (Li & Griffiths 2004, k = 4 so the quadric is an ellipsoid):
    ``(A, b)`` with A symmetric, ``|A (m - b)| = 1`` on the fitted surface.

    The samples are centred and scaled first (the 10 x 10 scatter of raw counts squared
    would lose precision) and the result mapped back.
    """
    m = np.asarray(m, dtype=float)
    c = m.mean(axis=0)
    s = float(np.sqrt(np.mean(np.sum((m - c) ** 2, axis=1))))
    if not s > 0:
        raise MagDegenerateError("the field samples do not vary: rotate the device through many orientations")
    x, y, z = ((m - c) / s).T
    D = np.array([x * x, y * y, z * z, 2 * y * z, 2 * x * z, 2 * x * y, 2 * x, 2 * y, 2 * z, np.ones_like(x)])
    S = D @ D.T
    S11, S12, S22 = S[:6, :6], S[:6, 6:], S[6:, 6:]
    k = 4.0
    C = np.zeros((6, 6))
    C[:3, :3] = k / 2 - 1
    np.fill_diagonal(C[:3, :3], -1.0)
    C[3:, 3:] = np.diag([-k, -k, -k])
    try:
        S22i_S21 = np.linalg.solve(S22, S12.T)
        E = np.linalg.solve(C, S11 - S12 @ S22i_S21)
    except np.linalg.LinAlgError:
        raise MagDegenerateError("the field samples determine no ellipsoid (too few distinct directions): "
                                 "rotate the device through many orientations") from None
    w, V = np.linalg.eig(E)
    i = int(np.argmax(w.real))
    v1 = V[:, i].real
    v2 = -S22i_S21 @ v1
    a, b_, c_, f, g, h = v1
    M = np.array([[a, h, g], [h, b_, f], [g, f, c_]])
    n, d = v2[:3], v2[3]
    if np.linalg.eigvalsh(M)[0] < 0:
        M, n, d = -M, -n, -d
    if np.linalg.eigvalsh(M)[0] <= 0:
        raise MagFitError("the field samples lie on no ellipsoid (the closed form gives a hyperboloid): "
                          "check the magnetometer columns and that the device was rotated, not moved near iron")
    centre = -np.linalg.solve(M, n)
    scale = float(centre @ M @ centre - d)
    if not scale > 0:
        raise MagFitError("the field samples lie on no ellipsoid (imaginary surface): check the columns")
    A = _sqrtm_spd(M / scale) / s
    return A, c + s * centre


def _residuals(theta, m, cov, bias_correct: bool):
    """Sampson residuals (noise units when ``cov`` is given, raw units otherwise) and the
    Gauss-Newton Jacobian (the weight's own derivative, zero at f = 0, left out)."""
    b, A = theta[:3], sym_from_vec(theta[3:])
    d = m - b
    u = d @ A.T
    r = np.linalg.norm(u, axis=1)
    nh = u / r[:, None]
    g = nh @ A  # ∇_m f = Aᵀ n̂
    Sig = np.eye(3) if cov is None else cov
    w = np.sqrt(np.einsum("ij,jk,ik->i", g, Sig, g))
    f = r - 1.0
    if bias_correct and cov is not None:
        ASA = A @ cov @ A.T
        f = f - 0.5 * (np.trace(ASA) - np.einsum("ij,jk,ik->i", nh, ASA, nh)) / r
    J = np.empty((m.shape[0], 9))
    J[:, :3] = -g
    # ∂f/∂A_jk = n̂_j d_k, both triangles for the off-diagonal entries of the symmetric A
    J[:, 3] = nh[:, 0] * d[:, 0]
    J[:, 4] = nh[:, 0] * d[:, 1] + nh[:, 1] * d[:, 0]
    J[:, 5] = nh[:, 0] * d[:, 2] + nh[:, 2] * d[:, 0]
    J[:, 6] = nh[:, 1] * d[:, 1]
    J[:, 7] = nh[:, 1] * d[:, 2] + nh[:, 2] * d[:, 1]
    J[:, 8] = nh[:, 2] * d[:, 2]
    return f / w, J / w[:, None]


def sampson_residuals(theta, samples: FieldSamples, bias_correct: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The residuals ``(n,)`` the fits minimise and their Jacobian ``(n, 9)`` in ``theta``
    (:data:`accelcal.mag.model.PARAMETERS`), in noise units when ``samples.noise_cov`` is known."""
    return _residuals(np.asarray(theta, float), samples.m, samples.noise_cov, bias_correct)


def information(theta, samples: FieldSamples) -> np.ndarray:
    """Fisher information ``JᵀJ`` of the nine parameters at ``theta`` (noise units;
    with unknown noise, per unit variance)."""
    _, J = _residuals(np.asarray(theta, float), samples.m, samples.noise_cov, False)
    return J.T @ J


def crlb(A, b, samples: FieldSamples) -> np.ndarray:
    """Cramér–Rao bound of the nine parameters for noise-free directions ``samples.m`` at the
    true ``(A, b)`` with noise ``samples.noise_cov``."""
    return np.linalg.inv(information(np.concatenate([b, vec_from_sym(A)]), samples))


def _result(theta, samples, method, iterations, notes=(), bias_correct=True) -> EllipsoidFit:
    r, J = _residuals(theta, samples.m, samples.noise_cov, bias_correct)
    dof = samples.n - 9
    sv = np.linalg.svd(J, compute_uv=False)
    chi2 = float(r @ r)
    known = samples.noise_cov is not None
    scale = chi2 / max(dof, 1)
    if known:
        # the measured noise explains the residual unless χ² rejects it (p < 0.01): then the
        # misfit is part of the error too, and the s.e. grow by sqrt(χ²/dof), as the accelerometer's
        scale = scale if dist.chi2_sf(chi2, max(dof, 1)) < 0.01 else 1.0
    inflate = 1.0 if samples.n_independent is None else max(samples.n / samples.n_independent, 1.0)
    cov = None
    if sv[-1] > 1e-12 * sv[0]:
        cov = np.linalg.inv(J.T @ J) * scale * inflate
    rraw, _ = _residuals(theta, samples.m, None, False)
    return EllipsoidFit(A=sym_from_vec(theta[3:]), b=theta[:3].copy(), method=method, cov=cov,
                        chi2=chi2 if known else None, dof=dof, residual_rms=float(np.sqrt(np.mean(rraw**2))),
                        singular_values=sv, iterations=iterations, notes=tuple(notes))


def fit_ellipsoid_lg(samples: FieldSamples) -> EllipsoidFit:
    """The closed form alone (Magneto's method): its covariance is the first-order one at
    the estimate, not that of the closed form (which is not efficient)."""
    A, b = li_griffiths(samples.m)
    return _result(np.concatenate([b, vec_from_sym(A)]), samples, "ellipsoid_lg", 0)


def fit_ellipsoid_ml(samples: FieldSamples, start: EllipsoidFit | None = None) -> EllipsoidFit:
    """Maximum likelihood (Gauss–Newton / trust region on the Sampson residuals) from the
    closed form (or ``start``)."""
    if start is None:
        start = fit_ellipsoid_lg(samples)
    theta0 = start.theta
    from scipy.optimize import least_squares  # here: scipy.optimize costs 0.2-0.6 s to import

    sol = least_squares(lambda th: _residuals(th, samples.m, samples.noise_cov, True)[0], theta0,
                        jac=lambda th: _residuals(th, samples.m, samples.noise_cov, True)[1],
                        method="lm", xtol=1e-12, ftol=1e-12, max_nfev=200)
    notes = () if sol.success else (f"ML refinement stopped: {sol.message}",)
    A = sym_from_vec(sol.x[3:])
    if np.linalg.eigvalsh(A)[0] <= 0:
        raise MagFitError("the refined soft-iron matrix is not positive definite: the samples do not "
                          "determine an ellipsoid (rotate through more orientations)")
    return _result(sol.x, samples, "ellipsoid_ml", int(sol.nfev), notes)


def fit_hard_iron(samples: FieldSamples) -> EllipsoidFit:
    """The nested model: a sphere (``A = a I``, hard iron and one scale), ML as above; its
    ``cov`` is over the nine parameters with the fixed ones at zero variance."""
    m = samples.m
    # closed-form sphere: |m|² = 2 bᵀm + (r² - |b|²), linear in (b, c)
    X = np.column_stack([2 * m, np.ones(len(m))])
    sol, *_ = np.linalg.lstsq(X, np.sum(m * m, axis=1), rcond=None)
    b0 = sol[:3]
    r0 = float(np.sqrt(max(sol[3] + b0 @ b0, 1e-300)))

    def full(p):
        return np.concatenate([p[:3], [p[3], 0, 0, p[3], 0, p[3]]])

    P = np.zeros((9, 4))
    P[:3, :3] = np.eye(3)
    P[[3, 6, 8], 3] = 1.0

    def res(p):
        r, J = _residuals(full(p), m, samples.noise_cov, True)
        return r, J @ P

    from scipy.optimize import least_squares  # here: scipy.optimize costs 0.2-0.6 s to import

    s = least_squares(lambda p: res(p)[0], np.concatenate([b0, [1 / r0]]), jac=lambda p: res(p)[1], method="lm")
    out = _result(full(s.x), samples, "hard_iron", int(s.nfev))
    r, J = res(s.x)
    known = samples.noise_cov is not None
    scale = 1.0 if known else float(r @ r) / max(samples.n - 4, 1)
    cov = P @ np.linalg.inv(J.T @ J) @ P.T * scale
    return replace(out, cov=cov, dof=samples.n - 4)


def with_residual_covariance(fit: EllipsoidFit, samples: FieldSamples) -> EllipsoidFit:
    """The fit with the covariance its residuals show when they scatter more than its own says.

    The covariance from the rests' noise assumes independent samples; over a whole session
    the residuals are correlated for hundreds of samples (SNU: a misfit that changes with
    the orientation, a field that differs from place to place) and the session-to-session
    scatter was 9-49x the s.e.  The block sandwich (:func:`accelcal.mag.noise.block_covariance`)
    holds for any such correlation: it replaces the covariance when the median of its
    variances exceeds the fit's own (a note says so), and the ellipsoid's 9 parameters only."""
    if fit.n_parameters != 9 or fit.cov is None:
        return fit
    r, J = _residuals(fit.theta, samples.m, samples.noise_cov, True)
    cov, info = block_covariance(J, r)
    if cov is None:
        return fit
    ratio = float(np.median(np.diag(cov) / np.maximum(np.diag(fit.cov), 1e-300)))
    if not ratio > 1.0:
        return fit
    note = (f"s.e. from the residuals' block sandwich ({info['blocks']} blocks; residuals correlated over "
            f"{info['correlation_length']} samples): {np.sqrt(ratio):.3g}x the noise-only s.e.")
    return replace(fit, cov=cov, notes=fit.notes + (note,))


__all__ = ["EllipsoidFit", "FieldSamples", "MIN_SAMPLES", "crlb", "fit_ellipsoid_lg", "fit_ellipsoid_ml",
           "fit_hard_iron", "information", "li_griffiths", "sampson_residuals",
           "with_residual_covariance"]
