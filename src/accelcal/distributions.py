"""The distribution functions the library uses, taken from ``scipy.special``.

``scipy.stats`` implements each of these as the special function named here, after
checking its arguments (see the ``_sf``/``_ppf``/``_isf`` methods in
``scipy/stats/_continuous_distns.py``).  Importing ``scipy.stats`` costs about 1 s of CPU,
and every process pays it: each workflow job and each ``accelcal`` call; importing
``scipy.special`` costs about 0.25 s, and happens at the first call that needs it.  The χ²
tail at a whole number of degrees of freedom, the one the calibration summary needs, is a
closed form in ``math``; the F tail at whole degrees of freedom (the gyro's g-sensitivity
test) is the regularised incomplete beta function by its continued fraction, in ``math``.  The functions return what ``scipy.stats`` returns, including
outside the support (``sf = 1`` below it) and for invalid degrees of freedom (NaN).
``tests/test_distributions.py`` checks them against ``scipy.stats``.
"""

from __future__ import annotations

import math

import numpy as np


class _LazySpecial:
    """``scipy.special``, imported at first use: the command line's calibration needs only
    :func:`chi2_sf` at a whole number of degrees of freedom (math below), and importing
    scipy.special costs ~0.25 s, half of ``accelcal calibrate`` on the Xsens session
    (measured again: importing the calibration and this module 0.189 s of CPU, with
    scipy.special 0.447 s, medians of 5 fresh processes)."""

    def __getattr__(self, name):
        from scipy import special as module

        return getattr(module, name)


special = _LazySpecial()


def _out(value):
    """A float for scalar input, an array otherwise (as scipy.stats returns)."""
    value = np.asarray(value, float)
    return float(value) if value.ndim == 0 else value


def _valid(*dofs):
    ok = np.ones((), bool)
    for d in dofs:
        ok = ok & (np.asarray(d, float) > 0)
    return ok


def _chi2_sf_whole(x: float, k: int) -> float:
    """``P(χ²_k > x)`` for a whole number ``k >= 1`` and ``x >= 0``, in closed form: with
    ``y = x/2``, ``e^-y Σ_{i<k/2} y^i/i!`` for even ``k``, and ``erfc(√y) + e^-y Σ_{i=1}^{(k-1)/2}
    y^(i-1/2)/Γ(i+1/2)`` for odd ``k``; each term in logarithms, so that neither ``e^-y`` nor
    the powers leave the floating-point range (the terms are positive: no cancellation)."""
    y = 0.5 * x
    if y == 0.0:
        return 1.0
    log_y = math.log(y)
    if k % 2 == 0:
        return math.fsum(math.exp(i * log_y - y - math.lgamma(i + 1)) for i in range(k // 2))
    return math.erfc(math.sqrt(y)) + math.fsum(math.exp((i - 0.5) * log_y - y - math.lgamma(i + 0.5))
                                               for i in range(1, (k + 1) // 2))


def chi2_sf(x, df):
    """Upper tail ``P(χ²_df > x)`` (``stats.chi2.sf``)."""
    if (np.ndim(x) == 0 and np.ndim(df) == 0 and float(df) == int(df) and 1 <= df <= 1000
            and math.isfinite(float(x))):
        return _chi2_sf_whole(max(float(x), 0.0), int(df))
    x, df = np.asarray(x, float), np.asarray(df, float)
    p = np.where(x < 0, 1.0, special.chdtrc(df, np.maximum(x, 0.0)))
    return _out(np.where(_valid(df), p, np.nan))


def chi2_isf(q, df):
    """``x`` with ``P(χ²_df > x) = q`` (``stats.chi2.isf``)."""
    return _out(np.where(_valid(df), special.chdtri(df, q), np.nan))


def chi2_ppf(q, df):
    """``x`` with ``P(χ²_df ≤ x) = q`` (``stats.chi2.ppf``)."""
    df = np.asarray(df, float)
    return _out(np.where(_valid(df), 2 * special.gammaincinv(df / 2, q), np.nan))


def _betainc_cf(a: float, b: float, x: float) -> float:
    """The continued fraction of the regularised incomplete beta ``I_x(a, b)`` (modified
    Lentz; Numerical Recipes 6.4), for ``x < (a + 1) / (a + b + 2)``, where it converges fast."""
    tiny, qab, qap, qam = 1e-300, a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 10000):
        for aa in (m * (b - m) * x / ((qam + 2 * m) * (a + 2 * m)),
                   -(a + m) * (qab + m) * x / ((a + 2 * m) * (qap + 2 * m))):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + aa / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-16:
            break
    front = math.exp(a * math.log(x) + b * math.log1p(-x) - (math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b)))
    return front * h / a


def _f_sf_whole(x: float, dfn: int, dfd: int) -> float:
    """``P(F > x)`` for whole degrees of freedom: ``I_w(dfd/2, dfn/2)``, ``w = dfd / (dfd + dfn x)``."""
    if x <= 0.0:
        return 1.0
    a, b = 0.5 * dfd, 0.5 * dfn
    w = dfd / (dfd + dfn * x)
    if w < (a + 1.0) / (a + b + 2.0):
        return _betainc_cf(a, b, w)
    return 1.0 - _betainc_cf(b, a, dfn * x / (dfd + dfn * x))  # 1 - w without its rounding


def f_sf(x, dfn, dfd):
    """Upper tail of the F distribution (``stats.f.sf``)."""
    if (np.ndim(x) == 0 and np.ndim(dfn) == 0 and np.ndim(dfd) == 0 and math.isfinite(float(x))
            and all(float(d) == int(d) and 1 <= d <= 10 ** 6 for d in (dfn, dfd))):
        return _f_sf_whole(float(x), int(dfn), int(dfd))
    x = np.asarray(x, float)
    p = np.where(x < 0, 1.0, special.fdtrc(dfn, dfd, np.maximum(x, 0.0)))
    return _out(np.where(_valid(dfn, dfd), p, np.nan))


def f_cdf(x, dfn, dfd):
    """``P(F ≤ x)`` (``stats.f.cdf``)."""
    x = np.asarray(x, float)
    p = np.where(x < 0, 0.0, special.fdtr(dfn, dfd, np.maximum(x, 0.0)))
    return _out(np.where(_valid(dfn, dfd), p, np.nan))


def f_isf(q, dfn, dfd):
    """``x`` with ``P(F > x) = q`` (``stats.f.isf``: ``fdtri`` at ``1 - q``)."""
    q = np.asarray(q, float)
    return _out(np.where(_valid(dfn, dfd), special.fdtri(dfn, dfd, 1.0 - q), np.nan))


def ncf_sf(x, dfn, dfd, nc):
    """Upper tail of the noncentral F distribution, ``1 - ncfdtr`` (``stats.ncf.sf``
    within 1e-13: both are Boost's noncentral beta; at ``nc = 0`` scipy 1.17's
    ``stats.ncf.sf`` returns ``-cdf``, this returns the central F's tail)."""
    x = np.asarray(x, float)
    p = np.where(x < 0, 1.0, 1.0 - special.ncfdtr(dfn, dfd, nc, np.maximum(x, 0.0)))
    return _out(np.where(_valid(dfn, dfd) & (np.asarray(nc, float) >= 0), p, np.nan))


def gamma_sf(x, a, scale=1.0):
    """Upper tail of the gamma distribution of shape ``a`` (``stats.gamma.sf``)."""
    y = np.asarray(x, float) / scale
    p = np.where(y < 0, 1.0, special.gammaincc(a, np.maximum(y, 0.0)))
    return _out(np.where(_valid(a) & (scale > 0), p, np.nan))


def gamma_ppf(q, a, scale=1.0):
    """Quantile of the gamma distribution of shape ``a`` (``stats.gamma.ppf``)."""
    return _out(np.where(_valid(a) & (scale > 0), special.gammaincinv(a, q) * scale, np.nan))


def beta_ppf(q, a, b):
    """Quantile of the beta distribution (``stats.beta.ppf``)."""
    return _out(np.where(_valid(a, b), special.betaincinv(a, b, q), np.nan))


def t_ppf(q, df):
    """Quantile of Student's t (``stats.t.ppf``; ``stdtrit`` gives +inf at ``q = 0``)."""
    q = np.asarray(q, float)
    return _out(np.where(_valid(df), np.where(q == 0, -np.inf, special.stdtrit(df, q)), np.nan))


def norm_ppf(q):
    """Quantile of the standard normal (``stats.norm.ppf``)."""
    return _out(special.ndtri(q))
