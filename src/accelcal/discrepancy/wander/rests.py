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

from .members import member_of

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
    #: ``(samples, intervals)`` the statistics came from: :attr:`full` computes its octaves
    #: from them on first use (only the ``sum`` family needs them, and the short octaves
    #: cost the most); None on a copy that has no source.
    source: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def full(self) -> RestAllan | None:
        """The same statistics at every octave from one sample up (what :mod:`.sums` fits
        the short part of a sum of processes to); computed once, on first use."""
        if self.source is None:
            return None
        if "full" not in self._cache:
            x, iv = self.source
            self._cache["full"] = _allan_at(x, iv, _octaves(iv), self.fs)
        return self._cache["full"]

    def member_avar(self, tau: float) -> np.ndarray:
        """``A_M(τ_k)`` (K,) of a unit member of the wander's grid (``tau``: its code,
        :meth:`.members.GridMember.rest_avar`; the per-placement offset is invisible in the rests)."""
        return member_of(tau).rest_avar(tau, self.taus, self.fs)

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
    lengths = iv[:, 1] - iv[:, 0]
    ms = _octaves(iv)
    if not ms or not np.all(np.isfinite(x)) or not fs > 0:
        return None
    # only the octaves the deviance keeps (the longest rest has blocks at every one of ms);
    # the short ones cost most and were dropped
    ms = [m for m in ms if m >= MIN_TAU_SHARE * float(np.median(lengths))]
    if not ms:
        return None
    return _allan_at(x, iv, ms, float(fs), source=(x, iv))


def _octaves(iv: np.ndarray) -> list[int]:
    """Every octave ``m`` (a power of two) at which the longest rest has :data:`MIN_BLOCKS` blocks."""
    longest = int(np.max(iv[:, 1] - iv[:, 0])) if len(iv) else 0
    ms = [1 << j for j in range(int(math.log2(max(longest // MIN_BLOCKS, 1))) + 1)]
    return [m for m in ms if longest // m >= MIN_BLOCKS]


def _allan_at(x: np.ndarray, iv: np.ndarray, ms, fs: float, source: tuple | None = None) -> RestAllan:
    """:class:`RestAllan` of ``x`` over the rests ``iv`` at the octaves ``ms`` (each held by
    the longest rest)."""
    lengths = iv[:, 1] - iv[:, 0]
    s2, cnt = np.zeros((3, len(ms))), np.zeros(len(ms))
    for k, m in enumerate(ms):
        parts = _octave_sums(x, iv, lengths, m)          # (n_rests, 3), zero where a rest has too few blocks
        for part in parts:  # summed in rest order, as one rest after another
            s2[:, k] += part
        cnt[k] = float(np.sum(np.where(lengths // m >= MIN_BLOCKS, lengths // m - 1, 0)))
    ms_arr = np.asarray(ms, float)
    return RestAllan(ms_arr, ms_arr / fs, s2 / cnt[None, :], np.broadcast_to(2.0 * cnt / 3.0, (3, len(ms))).copy(),
                     float(fs), source=source)


def _octave_sums(x: np.ndarray, iv: np.ndarray, lengths: np.ndarray, m: int) -> np.ndarray:
    """``½ Σ (ȳ_{j+1} − ȳ_j)²`` (n_rests, 3) over the blocks of ``m`` samples of each rest, the
    rests of one length at once (zero for a rest of fewer than :data:`MIN_BLOCKS` blocks)."""
    out = np.zeros((len(iv), 3))
    nbs = lengths // m
    for nb in np.unique(nbs[nbs >= MIN_BLOCKS]):
        idx = np.flatnonzero(nbs == nb)
        seg = x[iv[idx, 0][:, None] + np.arange(nb * m)[None, :]]         # (g, nb m, 3)
        y = seg.reshape(len(idx), nb, m, 3).mean(axis=2)
        d = np.diff(y, axis=1)
        out[idx] = 0.5 * np.sum(d * d, axis=1)
    return out


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
