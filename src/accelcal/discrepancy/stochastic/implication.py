"""What a noise model means for the static-pose means a calibration works with.

Pose-residual implication.  The deterministic calibration averages each static pose and
absorbs one common bias per axis, so what noise leaves in its residuals is the scatter
of the pose-mean errors about their common mean.  For poses ``i`` (start ``a_i``,
duration ``T_i``, disjoint, gap ``g_ij``) each term gives ``D_ij = Var(ē_i − ē_j)`` in
closed form:

* white ``N² (1/T_i + 1/T_j)``; quantization ``2Q² (1/T_i² + 1/T_j²)`` (``+ 2Q²/(T_i T_j)``
  if the intervals touch);
* random walk ``K² (g_ij + (T_i + T_j)/3)``; ramp ``R² (c_i − c_j)²`` (``c`` = mid times; a
  drift that lasts the whole session is the deterministic layer's bias drift);
* flicker ``−h₋₁ (F_i + F_j − 2 G_ij)`` with ``F = ln T − 3/2`` and ``G_ij`` the mean of
  ``ln|s − s'|`` over the two intervals (flicker's generalised covariance is
  ``−h₋₁ ln|t|``);
* Gauss–Markov ``W(T_i)/T_i² + W(T_j)/T_j² − 2σ²T_c² (1−e^{−T_i/T_c})(1−e^{−T_j/T_c}) e^{−g_ij/T_c}/(T_i T_j)``
  with ``W(T) = 2σ² (T_c T − T_c² (1 − e^{−T/T_c}))``;
* sinusoid (one coherent oscillation over the session, random phase)
  ``(A²/2) (s_i² + s_j² − 2 s_i s_j cos(2π f₀ (c_i − c_j)))`` with ``s = sin(π f₀ T)/(π f₀ T)``.

For adjacent equal intervals each reduces to ``2 AVAR(T)``.  The covariance of the
centred pose means is ``−½ P D P`` (``P = I − 11ᵀ/n``); its diagonal is the expected
squared pose-mean error per pose and axis.  A pose with unit gravity direction ``u``
sees ``Σ_axes u_a² v_a`` in its scalar residual (:func:`expected_residual_std`); the
nine calibration parameters absorb a little more than the common bias, so this slightly
overestimates the residual.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ...noise.terms import IntervalPairs, model_avar, noise_term, term_parameters
from .results import StochasticError, StochasticResult


def pose_difference_variance(term_id: str, value, starts, durations) -> np.ndarray:
    """``D_ij = Var(ē_i − ē_j)`` of one noise term's mean over disjoint intervals (module docstring).

    Parameters
    ----------
    term_id : str
    value : float or (float, float)
        The term's coefficient (``(coefficient, shape)`` for the two-parameter terms).
    starts, durations : array_like, shape (n,)
        Start [s] and duration [s] of each interval; intervals must not overlap.

    Returns
    -------
    ndarray, shape (n, n)
    """
    s, shape = term_parameters(term_id, value)
    a = np.asarray(starts, dtype=float)
    T = np.asarray(durations, dtype=float)
    if a.shape != T.shape or a.ndim != 1 or a.size == 0 or np.any(T <= 0):
        raise StochasticError("need 1-D starts and positive durations of the same length")
    order = np.argsort(a)
    if np.any(a[order][1:] < (a + T)[order][:-1] - 1e-9 * T.max()):
        raise StochasticError("pose intervals overlap")
    D = noise_term(term_id).interval_difference_variance(s**2, shape, IntervalPairs(a, T))
    D = np.array(D, dtype=float)
    np.fill_diagonal(D, 0.0)
    return D


def centred_pose_variance(D: np.ndarray) -> np.ndarray:
    """Diagonal of ``−½ P D P`` (``P = I − 11ᵀ/n``): variance of each pose-mean error about the common mean."""
    return D.mean(axis=1) - 0.5 * np.diag(D) - 0.5 * D.mean()


def pose_residual_implication(terms: Mapping[str, object], starts, durations, fs: float,
                              tau_max: float | None = None) -> dict:
    """What a noise model means for the pose means of a calibration session.

    Parameters
    ----------
    terms : mapping
        Noise model ``{id: coefficient}`` (two-parameter terms: ``(coefficient, shape)``).
    starts, durations : array_like
        Start and duration [s] of each static pose.
    fs : float
        Sampling rate [Hz].
    tau_max : float, optional
        Longest τ the noise model was fitted on: the session is usually much longer,
        and the drift of pose means over the session extrapolates the model's
        time-correlated terms from ``tau_max`` to the session length (reported as
        ``session_over_tau_max``).

    Returns
    -------
    dict
        ``pose_mean_std_white`` / ``_model``: RMS over poses of the expected error of a
        pose mean about the session's common mean, white term only / whole model (data
        unit); ``pose_mean_std_excess`` = sqrt of the difference of their squares (what
        the other terms add); ``by_term`` that RMS per term; ``inflation`` = model /
        white; ``adev_excess_at_median_duration`` = sqrt(AVAR_model(T) − N²/T) at the
        median pose duration T (extra std of a pose mean against an adjacent one);
        ``pose_mean_var_white`` / ``_model``: per-pose variances.  A ``gauss_markov``
        term with ``T_c`` below a tenth of the shortest pose is white noise seen through
        a low-pass filter at the scale of the poses: it counts as white here (with
        ``N² = 2σ²T_c``), not as excess.
    """
    starts = np.asarray(starts, dtype=float)
    durations = np.asarray(durations, dtype=float)
    per_term = {k: centred_pose_variance(pose_difference_variance(k, v, starts, durations))
                for k, v in terms.items()}
    white_like, n2_white = _white_like(terms, durations.min())
    v_white = np.sum([per_term[k] for k in white_like if k in per_term] or [np.zeros(starts.shape)], axis=0)
    v_model = np.sum(list(per_term.values()), axis=0)
    T = float(np.median(durations))
    excess_avar = model_avar(terms, [T], fs)[0] - n2_white / T
    return {
        "n_poses": int(starts.size),
        "session_length_s": float((starts + durations).max() - starts.min()),
        "median_pose_duration_s": T,
        "session_over_tau_max": (float((starts + durations).max() - starts.min()) / tau_max
                                 if tau_max else float("nan")),
        "pose_mean_std_white": float(np.sqrt(v_white.mean())),
        "pose_mean_std_model": float(np.sqrt(v_model.mean())),
        "pose_mean_std_excess": float(np.sqrt(max(v_model.mean() - v_white.mean(), 0.0))),
        "inflation": float(np.sqrt(v_model.mean() / v_white.mean())) if v_white.mean() > 0 else float("nan"),
        "by_term": {k: float(np.sqrt(max(v.mean(), 0.0))) for k, v in per_term.items()},
        "adev_excess_at_median_duration": float(np.sqrt(max(excess_avar, 0.0))),
        "pose_mean_var_white": v_white.tolist(),
        "pose_mean_var_model": v_model.tolist(),
    }


def _white_like(terms: Mapping[str, object], shortest: float) -> tuple[list[str], float]:
    """The terms that act as white noise at the scale of the poses (white, and a Gauss–Markov
    term with ``T_c`` below a tenth of the shortest pose: :meth:`~accelcal.noise.terms.NoiseTerm.white_level`)
    and their white level ``N²``."""
    levels = {k: noise_term(k).white_level(v, shortest) for k, v in terms.items()}
    white_like = [k for k, n2 in levels.items() if n2 is not None]
    return white_like, sum((n2 for n2 in levels.values() if n2 is not None), 0.0)


def expected_residual_std(result: StochasticResult, directions) -> dict:
    """Expected std of each pose's scalar calibration residual from the noise models, white only and full.

    ``directions``: (n_poses, 3) gravity direction of each pose in the sensor frame
    (e.g. the pose means, normalised), one row per segment of ``result``.  The residual
    ``‖M⁻¹(z − b)‖ − g`` of pose ``i`` moves by ``uᵢ · eᵢ`` for a pose-mean error ``eᵢ``,
    so its variance is ``Σ_a u_ia² v_ia`` with ``v`` the per-axis centred pose-mean
    variances of :func:`pose_residual_implication`.  Returns ``{"white": (n,), "model": (n,)}``.
    """
    if len(result.axes) != 3:
        raise StochasticError("expected_residual_std needs the three axes of an accelerometer")
    u = np.asarray(directions, dtype=float)
    if u.shape != (len(result.segment_lengths), 3) or not np.all(np.isfinite(u)) \
            or np.any(np.linalg.norm(u, axis=1) == 0):
        raise StochasticError(f"directions must be finite non-zero rows, shape ({len(result.segment_lengths)}, 3)")
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    out = {}
    for label in ("white", "model"):
        v = np.column_stack([a.pose_residual_implication[f"pose_mean_var_{label}"] for a in result.axes])
        out[label] = np.sqrt(np.sum(u**2 * v, axis=1))
    return out


__all__ = ["centred_pose_variance", "expected_residual_std", "pose_difference_variance", "pose_residual_implication"]
