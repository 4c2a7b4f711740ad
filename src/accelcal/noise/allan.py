"""Overlapping Allan variance of segmented rest data, pooled over segments.

A calibration session rests many times (the initial rest, then each pose), but never
for long: the longest rest of the public recordings lasts 36–52 s.  The Allan variance
is therefore computed per rest interval and pooled, which is legitimate because each
interval's overlapping estimator is an unbiased mean of squared second differences of
the same process (constant offsets between poses cancel in the second differences):

    AVAR(τ) = Σ_i S_i(τ) / Σ_i T_i(τ),   S_i = Σ_j (X_{j+2m} - 2 X_{j+m} + X_j)² / (2 τ²)

with ``X`` the running integral of segment ``i`` (``n_i + 1`` points), ``τ = m / fs``
and ``T_i = n_i + 1 - 2m`` terms (segments with ``T_i < 1`` drop out at that τ).
Pooling by the number of terms is the estimator one would get from one long record
cut into the same pieces.

Degrees of freedom.  The equivalent degrees of freedom (edf) of each segment's
estimate come from the approximations in NIST SP 1065 (Riley 2008, Table 5, overlapping
Allan variance, ``N = n_i + 1`` phase points) for the power-law noise types
``S_y(f) ∝ f^α`` (α = 2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2 random
walk FM); the pooled edf is Satterthwaite's for the weighted mean,
``ν = (Σ T_i)² / Σ (T_i² / ν_i)``.  The confidence interval of AVAR is the chi-square
one, ``[ν A / χ²_{(1+p)/2}(ν), ν A / χ²_{(1-p)/2}(ν)]``.

τ grid: octaves ``m = 1, 2, 4, …`` up to the largest ``m`` whose pooled white-FM edf is
at least ``min_edf`` (default 3: with a 52 s rest at 100 Hz the grid ends at
τ = 10.24 s, edf 5.7, where the 68 % interval of the Allan deviation is ×0.80 … ×1.51 of
the estimate; a 37 s rest also reaches 10.24 s, with edf 3.5 and ×0.77 … ×1.78).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import distributions as dist
from .. import kernels
from ..errors import AccelcalError

#: Power-law exponents α of S_y(f) ∝ f^α that :func:`edf_overlapping` knows.
NOISE_ALPHAS = (2, 1, 0, -1, -2)
#: Smallest pooled white-FM edf of a τ kept in the default grid (module docstring).
DEFAULT_MIN_EDF = 3.0

class AllanError(AccelcalError):
    """Segments that cannot give an Allan variance (too short, non-finite, wrong shape)."""


@dataclass(frozen=True)
class AllanVariance:
    """Pooled overlapping Allan variance of segmented data.

    Attributes
    ----------
    taus : ndarray, shape (k,)
        Averaging times [s], ``m / fs``.
    m : ndarray of int, shape (k,)
        Averaging factors (octaves).
    avar : ndarray, shape (k, d)
        Allan variance of each of the ``d`` columns, data unit squared.
    n_terms : ndarray of int, shape (k,)
        Second differences pooled at each τ (all segments).
    edf : ndarray, shape (k,)
        Pooled equivalent degrees of freedom assuming white FM (α = 0), the noise of a
        rate sensor at short τ; :meth:`edf_for` gives other noise types.
    fs : float
        Sampling rate [Hz].
    lengths : tuple of int
        Samples in each segment.
    """

    taus: np.ndarray
    m: np.ndarray
    avar: np.ndarray
    n_terms: np.ndarray
    edf: np.ndarray
    fs: float
    lengths: tuple[int, ...]

    @property
    def adev(self) -> np.ndarray:
        """Allan deviation, shape (k, d)."""
        return np.sqrt(self.avar)

    def edf_for(self, alpha: int) -> np.ndarray:
        """Pooled edf of each τ for power-law noise ``S_y ∝ f^alpha``, shape (k,)."""
        return pooled_edf(self.lengths, self.m, alpha)

    def adev_interval(self, level: float = 0.683, edf=None) -> tuple[np.ndarray, np.ndarray]:
        """Chi-square confidence interval of the Allan deviation, each shape (k, d).

        ``edf``: shape (k,) or (k, d); default the white-FM ``self.edf``.
        """
        edf = self.edf if edf is None else np.asarray(edf, dtype=float)
        edf = edf[:, None] if edf.ndim == 1 else edf
        lo, hi = avar_interval(self.avar, edf, level)
        return np.sqrt(lo), np.sqrt(hi)


def edf_overlapping(n: int, m, alpha: int) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping AVAR of one segment (NIST SP 1065, Table 5).

    Parameters
    ----------
    n : int
        Samples (rate data) in the segment; the formulas use ``N = n + 1`` phase points.
    m : int or array_like of int
        Averaging factors.
    alpha : int
        Power-law exponent of ``S_y(f) ∝ f^alpha`` (one of :data:`NOISE_ALPHAS`).

    Returns
    -------
    ndarray
        edf for each ``m``, 0 where the segment has no term (``n < 2m``), otherwise at
        least 1 (the approximations go below 1 only where one or two terms are left).
    """
    if alpha not in NOISE_ALPHAS:
        raise AllanError(f"unknown noise exponent alpha={alpha!r}; expected one of {NOISE_ALPHAS}")
    m = np.asarray(m, dtype=float)
    N = float(n + 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        if alpha == 2:
            edf = (N + 1) * (N - 2 * m) / (2 * (N - m))
        elif alpha == 1:
            edf = np.exp(np.sqrt(np.log((N - 1) / (2 * m)) * np.log((2 * m + 1) * (N - 1) / 4)))
        elif alpha == 0:
            edf = (3 * (N - 1) / (2 * m) - 2 * (N - 2) / N) * 4 * m**2 / (4 * m**2 + 5)
        elif alpha == -1:
            edf = np.where(m == 1, 2 * (N - 2) / (2.3 * N - 4.9), 5 * N**2 / (4 * m * (N + 3 * m)))
        else:
            edf = (N - 2) / m * ((N - 1) ** 2 - 3 * m * (N - 1) + 4 * m**2) / (N - 3) ** 2
    has_terms = n + 1 - 2 * m >= 1
    return np.where(has_terms, np.maximum(np.nan_to_num(edf, nan=1.0), 1.0), 0.0)


def pooled_edf(lengths: Sequence[int], m, alpha: int = 0) -> np.ndarray:
    """Satterthwaite edf of the term-weighted pooled AVAR, ``(Σ T_i)² / Σ (T_i² / ν_i)``."""
    m = np.atleast_1d(np.asarray(m, dtype=float))
    num = np.zeros(m.shape)
    den = np.zeros(m.shape)
    for n in lengths:
        terms = np.maximum(n + 1 - 2 * m, 0.0)
        nu = edf_overlapping(n, m, alpha)
        num += terms
        den += np.divide(terms**2, nu, out=np.zeros_like(terms), where=nu > 0)
    return np.divide(num**2, den, out=np.zeros_like(num), where=den > 0)


def avar_interval(avar, edf, level: float = 0.683) -> tuple[np.ndarray, np.ndarray]:
    """Chi-square confidence interval ``[ν A / χ²_{(1+p)/2}, ν A / χ²_{(1-p)/2}]`` of an AVAR estimate."""
    if not 0 < level < 1:
        raise AllanError(f"confidence level must be in (0, 1), got {level}")
    avar = np.asarray(avar, dtype=float)
    edf = np.broadcast_to(np.asarray(edf, dtype=float), avar.shape)
    lo = avar * edf / dist.chi2_ppf(0.5 + level / 2, edf)
    hi = avar * edf / dist.chi2_ppf(0.5 - level / 2, edf)
    return lo, hi


def octave_m(lengths: Sequence[int], min_edf: float = DEFAULT_MIN_EDF) -> np.ndarray:
    """Octave averaging factors ``1, 2, 4, …`` whose pooled white-FM edf is at least ``min_edf``."""
    longest = max(lengths)
    m = 2 ** np.arange(int(np.floor(np.log2(max(longest // 2, 1)))) + 1)
    keep = pooled_edf(lengths, m, 0) >= min_edf
    # edf falls monotonically with m, so the kept factors are a prefix of the octaves
    return m[: np.argmin(keep)] if not keep.all() else m


def check_segments(segments, fs: float) -> list[np.ndarray]:
    """Validate segmented data: a non-empty list of finite ``(n_i, d)`` arrays, the same ``d``, n_i ≥ 4."""
    if not (np.isfinite(fs) and fs > 0):
        raise AllanError(f"sampling rate must be positive and finite, got {fs}")
    if isinstance(segments, np.ndarray) and segments.ndim <= 2:
        segments = [segments]
    out = []
    for i, s in enumerate(segments):
        s = np.asarray(s, dtype=float)
        s = s[:, None] if s.ndim == 1 else s
        if s.ndim != 2 or s.shape[1] < 1:
            raise AllanError(f"segment {i} has shape {s.shape}; expected (n, d)")
        if not np.all(np.isfinite(s)):
            raise AllanError(f"segment {i} contains non-finite values")
        if s.shape[0] < 4:
            raise AllanError(f"segment {i} has {s.shape[0]} samples; need at least 4 for an Allan variance")
        out.append(s)
    if not out:
        raise AllanError("no segments given")
    d = {s.shape[1] for s in out}
    if len(d) != 1:
        raise AllanError(f"segments have different numbers of columns {sorted(d)}")
    return out


def allan_variance(segments, fs: float, *, m=None, min_edf: float = DEFAULT_MIN_EDF) -> AllanVariance:
    """Overlapping Allan variance of rate data in segments, pooled over segments.

    Parameters
    ----------
    segments : sequence of array_like, each shape (n_i,) or (n_i, d)
        Rest intervals (rate samples, any unit); offsets between segments do not matter.
    fs : float
        Sampling rate [Hz].
    m : array_like of int, optional
        Averaging factors; default :func:`octave_m`.
    min_edf : float
        Smallest pooled white-FM edf of a τ in the default grid.

    Returns
    -------
    AllanVariance

    Raises
    ------
    AllanError
        Empty or non-finite segments, segments shorter than 4 samples, no τ with
        enough degrees of freedom.
    """
    segs = check_segments(segments, fs)
    lengths = tuple(int(s.shape[0]) for s in segs)
    m = octave_m(lengths, min_edf) if m is None else np.atleast_1d(np.asarray(m, dtype=int))
    if m.size == 0 or np.any(m < 1):
        raise AllanError(f"no averaging time has pooled edf >= {min_edf:g}: the rests are too short "
                         f"(longest {max(lengths)} samples)")
    fast = kernels.compiled("noise._fast")

    d = segs[0].shape[1]
    sums = np.zeros((m.size, d))
    terms = np.zeros(m.size, dtype=np.int64)
    for s in segs:
        # Running sums of the centred data: the phase analogue (times fs); centring keeps
        # the digits of raw counts around 32768.
        n1 = s.shape[0] + 1
        reach = n1 - 2 * m >= 1
        if fast is not None:  # the same sums, running sums included, compiled (accelcal[fast])
            sums[reach] += fast.allan_sums(s, s.mean(axis=0), m[reach]) / (2.0 * m[reach, None] ** 2)
        else:
            c = np.concatenate([np.zeros((1,) + s.shape[1:]), np.cumsum(s - s.mean(axis=0), axis=0)])
            buf = np.empty_like(c)  # c[i+2m] − 2 c[i+m] + c[i] in place: no 3 temporaries per m
            for k in np.flatnonzero(reach):
                mk = m[k]
                dd = buf[: c.shape[0] - 2 * mk]
                np.multiply(c[mk:-mk], 2.0, out=dd)
                np.subtract(c[2 * mk:], dd, out=dd)
                np.add(dd, c[: c.shape[0] - 2 * mk], out=dd)
                sums[k] += np.einsum("ij,ij->j", dd, dd) / (2.0 * mk * mk)
        terms[reach] += n1 - 2 * m[reach]
    if np.any(terms == 0):
        raise AllanError(f"averaging factor m={int(m[np.argmax(terms == 0)])} is longer than half of every segment")
    return AllanVariance(taus=m / float(fs), m=m.astype(int), avar=sums / terms[:, None], n_terms=terms,
                         edf=pooled_edf(lengths, m, 0), fs=float(fs), lengths=lengths)


__all__ = ["AllanError", "AllanVariance", "DEFAULT_MIN_EDF", "NOISE_ALPHAS", "allan_variance", "avar_interval",
           "check_segments", "edf_overlapping", "octave_m", "pooled_edf"]
