"""The closed forms of :mod:`accelcal.lls` over many trials at once (Monte Carlo): ``z`` of
shape ``(trials, poses, 3)``, a :class:`~accelcal.results.BatchResult` whose invalid
trials hold NaN and the name of the error the single-problem estimator raises."""

from __future__ import annotations

import numpy as np

from .errors import DegeneratePosesError, NonFiniteError, NotPositiveDefiniteError
from .kernels import compiled
from .lls import _KERNELS, _NON_FINITE, EIGVEC_TOL, MIN_GAP, _float_or_nan, _scale, design_matrix, theta_to_model
from .results import BatchResult
from .validation import check_finite, check_g, degenerate_trials, pose_array


def full_lls_batch(z, g: float) -> BatchResult:
    """Full LLS over many trials at once: ``z`` of shape ``(trials, poses, 3)``.

    Trials whose estimate is not an ellipsoid are marked ``valid=False``, hold NaN and
    have the status ``'NotPositiveDefiniteError'`` (what :func:`full_lls` raises).
    The estimate of each trial is that of the SVD (:func:`_full_lls_batch_svd`, the
    reference); the compiled kernel computes it by the certified Gram-matrix route of
    :func:`full_lls` and hands the trials it cannot certify to the SVD.
    """
    K = compiled(_KERNELS)
    z = pose_array(z, "full", batched=True)
    if K is None:
        check_finite(z)
        return _refuse_degenerate(_full_lls_batch_svd(z, check_g(g)), z)
    z = np.ascontiguousarray(z)
    T = len(z)
    bias, M, status, clear = np.empty((T, 3)), np.empty((T, 3, 3)), np.empty(T, np.int8), np.empty(T, bool)
    K.full_lls_batch(z, _float_or_nan(g), MIN_GAP, EIGVEC_TOL, bias, M, status, clear)
    if (status == K.NON_FINITE).any():
        raise NonFiniteError(_NON_FINITE)
    g = check_g(g)
    ref = np.flatnonzero(status == K.REFERENCE)
    valid = status == K.OK
    if len(ref):
        r = _full_lls_batch_svd(z[ref], g)
        bias[ref], M[ref], valid[ref] = r.bias, r.M, r.valid
    return _refuse_degenerate(BatchResult(method="full_lls", bias=bias, M=M, valid=valid,
                                          status=_status(valid, NotPositiveDefiniteError)), z, clear)


def _refuse_degenerate(r: BatchResult, z, clear=None) -> BatchResult:
    """The trials whose poses the single-problem estimators refuse as degenerate (nearly
    coplanar, along one axis, identical): NaN, invalid, ``DegeneratePosesError``.
    ``clear``: the trials the kernel's moment screen passed, which need no further check."""
    bad = degenerate_trials(z, clear)
    if bad.any():
        r.bias[bad], r.M[bad], r.valid[bad] = np.nan, np.nan, False
        r.status[bad] = DegeneratePosesError.__name__
    return r


def _full_lls_batch_svd(z, g: float) -> BatchResult:
    """Reference batched full LLS: SVD of every scaled design matrix (eq. 3), eqs. (4)-(6)."""
    k = _scale(z)
    X = design_matrix(z / k[:, None, None])
    _, _, Vt = np.linalg.svd(X, full_matrices=False)
    b, M, _, valid = theta_to_model(Vt[:, -1, :], g / k)
    return BatchResult(method="full_lls", bias=b * k[:, None], M=M, valid=valid,
                       status=_status(valid, NotPositiveDefiniteError))


def _status(valid: np.ndarray, error: type) -> np.ndarray:
    """``'ok'`` per valid trial, else the name of the error the single-problem estimator raises."""
    return np.where(valid, "ok", error.__name__)


def bias_lls_batch(z, g: float) -> BatchResult:
    """Bias-only LLS over many trials at once: ``z`` of shape ``(trials, poses, 3)``.

    Trials whose poses do not determine the bias (singular normal equations) are marked
    ``valid=False``, hold NaN and have the status ``'DegeneratePosesError'``.  The
    compiled kernel solves each trial by the centred normal equations of
    :func:`bias_lls` and hands the trials whose scatter is not
    clearly three-dimensional to the reference (:func:`_bias_lls_batch_normal`).
    """
    K = compiled(_KERNELS)
    z = pose_array(z, "bias", batched=True)
    if K is None:
        check_finite(z)
        check_g(g)
        return _refuse_degenerate(_bias_lls_batch_normal(z), z)
    z = np.ascontiguousarray(z)
    T = len(z)
    bias, M, status, clear = np.empty((T, 3)), np.empty((T, 3, 3)), np.empty(T, np.int8), np.empty(T, bool)
    K.bias_lls_batch(z, bias, M, status, clear)
    if (status == K.NON_FINITE).any():
        raise NonFiniteError(_NON_FINITE)
    check_g(g)
    valid = status == K.OK
    ref = np.flatnonzero(status == K.REFERENCE)
    if len(ref):
        r = _bias_lls_batch_normal(z[ref])
        bias[ref], valid[ref] = r.bias, r.valid
    return _refuse_degenerate(BatchResult(method="bias_lls", bias=bias, M=M, valid=valid,
                                          status=_status(valid, DegeneratePosesError)), z, clear)


def _bias_lls_batch_normal(z) -> BatchResult:
    """Reference batched bias-only LLS: normal equations of the scaled eq. (7)."""
    k = _scale(z)
    zs = z / k[:, None, None]
    H = np.concatenate([2 * zs, np.ones(zs.shape[:-1] + (1,))], axis=-1)
    y = np.sum(zs**2, axis=-1)
    # Normal equations of a 4-column system scaled to O(1): condition² stays small.
    HtH = np.einsum("tni,tnj->tij", H, H)
    Hty = np.einsum("tni,tn->ti", H, y)
    T = len(z)
    # a trial whose normal equations are singular to working precision (all poses equal,
    # noise-free poses in one plane) determines no bias: NaN and valid=False, not an
    # exception for the whole batch nor digits of rounding noise
    valid = np.linalg.cond(HtH) < 1.0 / np.finfo(float).eps
    sol = np.full((T, 4), np.nan)
    if valid.any():
        sol[valid] = np.linalg.solve(HtH[valid], Hty[valid][..., None])[..., 0]
    return BatchResult(method="bias_lls", bias=sol[:, :3] * k[:, None],
                       M=np.broadcast_to(np.eye(3), (T, 3, 3)).copy(), valid=valid,
                       status=_status(valid, DegeneratePosesError))
