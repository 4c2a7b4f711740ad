"""accelcal.distributions returns what scipy.stats returns, inside and outside the support,
and the core library does not import scipy.stats (it costs every process ~1 s of CPU)."""

import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from accelcal import distributions as D

X = np.array([-1.0, 0.0, 1e-6, 0.3, 1.0, 2.5, 7.0, 40.0, np.inf, np.nan])
Q = np.array([0.0, 1e-9, 0.005, 0.025, 0.3, 0.5, 0.95, 0.999, 1.0, np.nan])
DOF = [-1, 0, 0.5, 1, 3, 7.5, 30, 400]


def same(a, b):
    np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), rtol=1e-13, atol=1e-15, equal_nan=True)


@pytest.mark.parametrize("df", DOF)
def test_chi2_and_t(df):
    with np.errstate(all="ignore"):
        same(D.chi2_sf(X, df), stats.chi2.sf(X, df))
        same(D.chi2_isf(Q, df), stats.chi2.isf(Q, df))
        same(D.chi2_ppf(Q, df), stats.chi2.ppf(Q, df))
        same(D.t_ppf(Q, df), stats.t.ppf(Q, df))
        same(D.gamma_sf(X, df, scale=0.7), stats.gamma.sf(X, df, scale=0.7))
        same(D.gamma_ppf(Q, df, scale=0.7), stats.gamma.ppf(Q, df, scale=0.7))


@pytest.mark.parametrize("dfn,dfd", [(1, 1), (3, 20), (9, 0), (0, 5), (2.5, 300)])
def test_f_ncf_beta(dfn, dfd):
    with np.errstate(all="ignore"):
        same(D.f_sf(X, dfn, dfd), stats.f.sf(X, dfn, dfd))
        same(D.f_cdf(X, dfn, dfd), stats.f.cdf(X, dfn, dfd))
        same(D.f_isf(Q, dfn, dfd), stats.f.isf(Q, dfn, dfd))
        same(D.beta_ppf(Q, dfn, dfd), stats.beta.ppf(Q, dfn, dfd))
        for nc in (0.1, 1.5, 30.0):
            np.testing.assert_allclose(D.ncf_sf(X, dfn, dfd, nc), stats.ncf.sf(X, dfn, dfd, nc), rtol=0, atol=1e-13,
                                       equal_nan=True)
        # nc = 0 is the central F (scipy 1.17's stats.ncf.sf returns -cdf there)
        np.testing.assert_allclose(D.ncf_sf(X, dfn, dfd, 0.0), stats.f.sf(X, dfn, dfd), rtol=0, atol=1e-13,
                                   equal_nan=True)
    same(D.norm_ppf(Q), stats.norm.ppf(Q))


def test_scalar_in_float_out():
    assert type(D.chi2_sf(3.0, 2)) is float and type(D.beta_ppf(0.5, 2, 3)) is float
    assert D.chi2_sf([1.0, 2.0], 2).shape == (2,)


def test_the_core_library_does_not_import_scipy_stats():
    """The CLI and the discrepancy analysis must not pay scipy.stats' import (or
    scipy.signal's: 1 s each) at import time."""
    code = ("import sys, accelcal.cli, accelcal.discrepancy, accelcal.calibration, accelcal.evaluation; "
            "print(sorted(m for m in ('scipy.stats', 'scipy.signal') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out
