"""A sum of processes: the wander's short part pinned by the rests, its long part from the poses.

The wander of a real sensor is often a sum: Gauss–Markov components from seconds to
minutes (a flicker-like Allan floor), a random walk, a per-placement offset.  One member
of the grid (:mod:`.problem`) stands for all of them, fitted from ~30 pose means.  But
the components shorter than a rest show in every rest's own samples, hundreds to
thousands of them: their Allan variance within the rests measures them far better than
the pose means can, and a deterministic effect between the poses cannot leak into it.

Model (wander family ``sum``).  Per axis, the noise is white + a short Gauss–Markov
component (size ``σ_s``, correlation time ``τ_s``) + one long member of the grid (flicker,
per-placement offset, Gauss–Markov, random walk; REML from the poses as in the other
families) + the calibration's own effects:

* The short component is fitted to the rests' Allan variances at every octave from one
  sample up (:attr:`.rests.RestAllan.full`, the χ² deviance of :func:`.rests.rest_deviance`,
  the white level of each axis profiled), ``τ_s`` on :data:`SHORT_TAUS_PER_OCTAVE` per octave
  from the sample interval to the longest octave measured, and kept only when the rests
  demand it: its deviance gain over white noise exceeds :data:`SHORT_EVIDENCE` (a
  likelihood-ratio test of two parameters at about 0.1 %, the grid of ``τ_s`` counted).
  It is a Gauss–Markov process, never a flicker or a random walk: a bump of the rests'
  Allan deviation at 0.08 s (the IMU-TK fork's sessions) is then a component of 0.08 s,
  which reaches no other pose, instead of a 1/f floor extrapolated to minutes (what made
  ``flicker_rests`` name outliers on those sessions).
* Its covariance between the pose means is exact (interval means of a Gauss–Markov
  process, :func:`.problem.wander_kernel`), less each pose mean's own variance, which the
  pose's standard error already holds (it is computed from the pose's own samples with
  their autocorrelation: :mod:`accelcal.static`).  In the contrasts (package docstring,
  "Linear model") it is ``C_s``, and the base covariance of the pose residuals is
  ``B = I + C_s`` instead of ``I``.
* The problem is rewritten in ``B``'s whitened contrasts, ``y' = B^{-1/2} y`` (the
  contrast map ``L`` becomes ``L B^{-1/2}``): there the covariance is ``s (I + q K'_τ)``,
  the other families' form, so REML of ``(s, q, τ, φ)``, the likelihood-ratio tests, the
  outlier family and the bootstrap run unchanged, and the bootstrap's nulls are drawn
  from the whole chosen model ``s (B + q K_τ)``.  The white scale ``s`` multiplies the
  short part too (the rests measured both with the same standard errors).

A plug-in, not a joint maximum: the short part is fixed at the rests' estimate (thousands
of samples; its standard error is small beside the pose residuals'), the long part and
``s`` are estimated from the poses given it.  Without the rests' samples (pose means only)
or without evidence for a short component, the family is ``flicker``'s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .members import member_of
from .problem import Problem, wander_kernel
from .rests import RestAllan, rest_deviance

#: Correlation times of the short component per octave of averaging time.
SHORT_TAUS_PER_OCTAVE = 2
#: Sizes of the short component's variance tried, relative to the per-sample white variance.
SHORT_Q_GRID = np.logspace(-5.0, 1.0, 49)
#: Deviance gain (white → white + short component) the rests must show for the component:
#: χ²₂ at 0.1 % is 13.8; the grid of τ_s makes the largest gain a maximum over ~20 tests.
SHORT_EVIDENCE = 20.0
#: Smallest eigenvalue of the base covariance ``B`` kept (round-off, and a short part whose
#: pose-mean variance the standard errors caught only in part).
MIN_BASE_EIGENVALUE = 1e-3


@dataclass(frozen=True)
class ShortPart:
    """The short component the rests pin: a Gauss–Markov process of variance ``q_abs``
    [data unit², per axis] and correlation time ``tau`` [s]; ``gain`` the rests' deviance
    gain over white noise."""

    tau: float
    q_abs: float
    gain: float

    def describe(self) -> str:
        return (f"sum of processes: a Gauss-Markov component of tau {self.tau:.3g} s and std "
                f"{np.sqrt(self.q_abs):.3g} (data unit) pinned by the rests' Allan variances (deviance gain "
                f"{self.gain:.1f} over white noise), the long member from the pose residuals")


def short_taus(ra: RestAllan) -> np.ndarray:
    """The grid of ``τ_s``: from the sample interval to the longest octave measured."""
    lo, hi = 1.0 / ra.fs, float(ra.taus.max())
    k = max(int(np.ceil(np.log2(hi / lo) * SHORT_TAUS_PER_OCTAVE)), 1)
    return np.geomspace(lo, hi, k + 1)


def fit_short(ra: RestAllan | None) -> ShortPart | None:
    """The short component the rests' Allan variances ``ra`` (every octave) demand, or None
    (no rests, too few octaves, or no evidence beyond white noise: :data:`SHORT_EVIDENCE`)."""
    if ra is None or ra.taus.size < 3:
        return None
    if "short" not in ra._cache:  # the rests are the same in every round of the loop
        ra._cache["short"] = _fit_short(ra)
    return ra._cache["short"]


def _fit_short(ra: RestAllan) -> ShortPart | None:
    from_white = float(rest_deviance(ra, np.zeros(ra.taus.size)))
    taus = short_taus(ra)
    unit = np.stack([ra.member_avar(t) for t in taus])                             # (T, K)
    white = float(np.mean(ra.avar[:, 0] * ra.m[0]))                                # per-sample variance
    q = white * SHORT_Q_GRID                                                       # (Q,)
    dev = rest_deviance(ra, q[None, :, None] * unit[:, None, :])                   # (T, Q)
    t, k = np.unravel_index(int(np.argmin(dev)), dev.shape)
    gain = from_white - float(dev[t, k])
    if gain < SHORT_EVIDENCE:
        return None
    return ShortPart(float(taus[t]), float(q[k]), gain)


def pose_covariance(short: ShortPart, starts, durations, grad) -> np.ndarray:
    """Covariance (n, n) of the pose residuals from the short component, less each pose
    mean's own variance (already in its standard error; module docstring)."""
    K = wander_kernel(short.tau, starts, durations, grad)        # its diagonal is the bias's business
    # the variance of a unit process's interval mean (the short part is a Gauss-Markov member)
    own = member_of(short.tau).interval_variance(short.tau, np.asarray(durations, float))
    gdiag = np.sum(np.asarray(grad, float) ** 2, axis=1)
    return short.q_abs * (K - np.diag(gdiag * own))


def pinned(prob: Problem, short: ShortPart) -> Problem:
    """``prob`` in the whitened contrasts of ``B = I + C_s`` (module docstring), before its
    kernels are diagonalised (``fit_common`` does that, as for every family)."""
    Lw = prob.L / prob.sigma[:, None]
    Cs = Lw.T @ pose_covariance(short, prob.starts, prob.durations, prob.grad) @ Lw
    ev, V = np.linalg.eigh(0.5 * (Cs + Cs.T) + np.eye(prob.m))
    R = (V / np.sqrt(np.clip(ev, MIN_BASE_EIGENVALUE, None))) @ V.T                # B^{-1/2}
    return replace(prob, y=R @ prob.y, X0=R @ prob.X0, L=prob.L @ R, notes=(*prob.notes, short.describe()),
                   rests=None)


__all__ = ["MIN_BASE_EIGENVALUE", "SHORT_EVIDENCE", "SHORT_Q_GRID", "SHORT_TAUS_PER_OCTAVE", "ShortPart",
           "fit_short", "pinned", "pose_covariance", "short_taus"]
