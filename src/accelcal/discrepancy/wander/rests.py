"""What the rests' own samples say about the wander: the joint likelihood's second part.

The pose residuals give the wander from ~30 pose means; every rest also holds hundreds
of samples, whose scatter about the rest's mean shows the same noise at averaging times
up to the rest's length.  A member of the wander's family predicts that scatter: its
Allan variance ``A_M(τ)`` adds to the white noise's ``N²/τ`` (a flicker bias a flat floor
``(2 ln 2/π) B²``, a random walk ``K²τ/3``, a Gauss–Markov process its own curve, a
per-placement offset nothing: it is constant within a rest).  So the rests can tell
members apart that the pose means alone cannot: a flicker floor and a random walk of the
same size between the poses differ by a factor of ten or more within the rests.

Statistic (:func:`rest_allan`).  Per axis and octave ``m = 1, 2, 4, …`` samples (``τ =
m/f_s``, at least four blocks in a rest, and at least a tenth of the median rest:
:data:`MIN_TAU_SHARE`), the non-overlapping Allan variance pooled over
the rests: ``Â(τ) = Σ ½ (ȳ_{j+1} − ȳ_j)² / c`` over the ``c`` consecutive block pairs
inside each rest (none across a motion), each rest's blocks about its own samples (the
rest's level, whatever it is, cancels in the differences).

Likelihood (:func:`rest_deviance`).  ``Â(τ_k) ~ A(τ_k) χ²_ν/ν`` with ``A = N_a² /m_k +
q_abs A_M(τ_k)`` (``N_a²`` the white variance of axis ``a`` at the octaves used, profiled
on a grid around ``m Â`` of the first of them) and ``ν = 2c/3`` (adjacent differences share a block:
the white-noise correlation of their squares, 1/4, counted on both sides).  ``−2ℓ =
Σ_k ν_k (log A_k + Â_k/A_k)`` summed over the axes, the same wander size on every axis
(the pose model's).  The octaves are treated as independent (they are nearly so for white
noise, less for a wander that dominates several of them: the deviance then counts its
evidence more than once; the benchmark measures what that costs).

How it joins the pose likelihood (:meth:`RestAllan.deviance_grid`).  On the grid of the
wander (member ``t``, relative size ``q``) the rests' deviance is evaluated at ``q_abs =
q / scale_t``, i.e. at the white scale 1 (the rests' standard errors are right: the
pose model's ``ŝ`` is kept within [0.5, 4] of it), and added to ``log|Σ|`` of every
likelihood surface of the round (:func:`.gls.profile`): REML, the tests' likelihood ratios
and their bootstrap replicates.  The replicates keep the data's rests: the bootstrap is
conditional on them (within-rest differences are independent of the pose means for white
noise, and nearly so for a wander slower than a rest).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...noise.terms import model_avar

#: Fewest blocks of one octave a rest must hold for that octave (three differences).
MIN_BLOCKS = 4
#: Only octaves of at least this share of the median rest enter the deviance: the time
#: scales near the poses'.  Shorter ones carry what a real sensor's filter and vibration do
#: within a fraction of a second (the IMU-TK fork sessions' rests show an Allan bump at
#: 0.08 s, 1.4-4.4 times white noise), which no wander member extrapolates to minutes:
#: with every octave in, those sessions' joint fit chose a flicker the pose residuals do not
#: show and named two outlier poses the pose residuals alone did not.
MIN_TAU_SHARE = 0.1
#: Grid of the per-sample white variance, relative to ``m Â`` at the first octave used,
#: that the rests' deviance is profiled over (free: the white level is not taken from the
#: shortest octaves).
WHITE_FACTORS = np.geomspace(0.3, 1.5, 61)


@dataclass(frozen=True)
class RestAllan:
    """The rests' pooled non-overlapping Allan variances (module docstring).

    ``m`` (K,) block lengths [samples], ``taus`` (K,) = ``m/fs`` [s], ``avar`` (3, K) per
    axis [data unit²], ``dof`` (3, K) the χ² degrees of freedom ``ν`` of each; only the
    octaves of at least :data:`MIN_TAU_SHARE` of the median rest are kept.
    """

    m: np.ndarray
    taus: np.ndarray
    avar: np.ndarray
    dof: np.ndarray
    fs: float
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    #: The same statistics at every octave from one sample up (what :mod:`.sums` fits the
    #: short part of a sum of processes to); None on a restricted copy.
    full: RestAllan | None = field(default=None, repr=False, compare=False)

    def member_avar(self, tau: float) -> np.ndarray:
        """``A_M(τ_k)`` (K,) of a unit member of the wander's grid (``tau``: its code,
        :func:`~.problem.tau_grid`; the per-placement offset is invisible in the rests)."""
        if tau == 0.0:
            return np.zeros(self.taus.size)
        if tau == -1.0:
            return model_avar({"bias_instability": 1.0}, self.taus, self.fs)
        if np.isinf(tau):
            return model_avar({"random_walk": 1.0}, self.taus, self.fs)
        return model_avar({"gauss_markov": (1.0, float(tau))}, self.taus, self.fs)

    def deviance_grid(self, taus, scale, qrel) -> np.ndarray:
        """The rests' ``−2ℓ`` on the wander's grid (T, Q), at ``q_abs = q/scale_t``
        (module docstring), less its minimum; cached per grid."""
        taus, scale, qrel = (np.asarray(a, float) for a in (taus, scale, qrel))
        key = (taus.tobytes(), scale.tobytes(), qrel.tobytes(), qrel.shape)
        out = self._cache.get(key)
        if out is None:
            q = np.broadcast_to(qrel, (taus.size, qrel.shape[-1]))
            M = np.stack([self.member_avar(t) for t in taus])                  # (T, K)
            q_abs = q / np.where(scale > 0, scale, 1.0)[:, None]                # (T, Q)
            out = rest_deviance(self, q_abs[:, :, None] * M[:, None, :])
            out = out - out.min()
            self._cache[key] = out
        return out


def rest_allan(samples, intervals, fs: float) -> RestAllan | None:
    """:class:`RestAllan` of ``samples`` (n, 3) [data unit] over the rests ``intervals``
    (n_rests, 2) ``[start, stop)`` sample indices at ``fs`` [Hz]; None when no rest holds
    :data:`MIN_BLOCKS` samples."""
    x = np.asarray(samples, float)
    iv = np.asarray(intervals, int)
    longest = int(np.max(iv[:, 1] - iv[:, 0])) if len(iv) else 0
    ms = [1 << j for j in range(int(math.log2(max(longest // MIN_BLOCKS, 1))) + 1)]
    ms = [m for m in ms if longest // m >= MIN_BLOCKS]
    if not ms or not np.all(np.isfinite(x)) or not fs > 0:
        return None
    s2, cnt = np.zeros((3, len(ms))), np.zeros(len(ms))
    for a0, a1 in iv:
        seg = x[a0:a1]
        for k, m in enumerate(ms):
            nb = len(seg) // m
            if nb < MIN_BLOCKS:
                break
            y = seg[:nb * m].reshape(nb, m, 3).mean(axis=1)
            d = np.diff(y, axis=0)
            s2[:, k] += 0.5 * np.sum(d * d, axis=0)
            cnt[k] += nb - 1
    ms_arr = np.asarray(ms, float)
    some = cnt > 0
    full = RestAllan(ms_arr[some], ms_arr[some] / fs, s2[:, some] / cnt[None, some],
                     np.broadcast_to(2.0 * cnt[some] / 3.0, (3, int(some.sum()))).copy(), float(fs))
    keep = (ms_arr >= MIN_TAU_SHARE * float(np.median(iv[:, 1] - iv[:, 0]))) & some
    if not keep.any():
        return None
    return RestAllan(ms_arr[keep], ms_arr[keep] / fs, s2[:, keep] / cnt[None, keep],
                     np.broadcast_to(2.0 * cnt[keep] / 3.0, (3, int(keep.sum()))).copy(), float(fs), full=full)


def rest_deviance(ra: RestAllan, wander_avar: np.ndarray) -> np.ndarray:
    """``−2ℓ`` of the rests (module docstring), summed over the axes, for the wander's Allan
    variances ``wander_avar`` (..., K) [data unit²], the white level of each axis profiled
    over :data:`WHITE_FACTORS` × ``m Â`` of the first octave."""
    out = 0.0
    for a in range(ra.avar.shape[0]):
        A_hat, nu = ra.avar[a], ra.dof[a]
        n2 = WHITE_FACTORS * A_hat[0] * ra.m[0]                          # (F,) per-sample white variance
        A = n2[:, None] / ra.m[None, :] + wander_avar[..., None, :]      # (..., F, K)
        dev = np.sum(nu * (np.log(A) + A_hat / A), axis=-1)              # (..., F)
        out = out + dev.min(axis=-1)
    return out


__all__ = ["MIN_BLOCKS", "RestAllan", "WHITE_FACTORS", "rest_allan", "rest_deviance"]
