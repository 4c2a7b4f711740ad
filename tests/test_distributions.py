"""accelcal.distributions returns what scipy.stats returns, inside and outside the support,
and the core library does not import scipy.stats (it costs every process ~1 s of CPU)."""

import subprocess
import sys
from pathlib import Path

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


@pytest.mark.parametrize("k", [1, 2, 3, 9, 10, 29, 100, 401, 1000])
def test_chi2_tail_at_whole_degrees_of_freedom_in_closed_form(k):
    """The scalar χ² tail at a whole number of degrees of freedom (math, no scipy): within
    1e-12 of scipy's, down to tails of 1e-300 (each term is taken in logarithms)."""
    for x in np.concatenate([[0.0, 1e-300, 1e-9], np.linspace(0.01, 3 * k + 100, 300)]):
        want = stats.chi2.sf(x, k)
        if want > 1e-300:
            assert D.chi2_sf(float(x), k) == pytest.approx(want, rel=1e-12, abs=0), (k, x)
    assert D.chi2_sf(-1.0, k) == 1.0 and D.chi2_sf(0.0, k) == 1.0


@pytest.mark.parametrize("dfn,dfd", [(1, 1), (9, 18), (9, 27), (9, 85), (2, 7), (30, 3), (400, 1000)])
def test_f_tail_at_whole_degrees_of_freedom_in_math(dfn, dfd):
    """The scalar F tail at whole degrees of freedom (math: the incomplete beta's continued
    fraction, no scipy): within 1e-11 of scipy's, down to tails of 1e-300, or 1e-10 absolute
    near 1, where scipy's own fdtrc is off by 3e-11 (F(1, 1) at 1e-12: 1 - 2 atan(1e-6) / pi
    = 0.99999936338022766, scipy 0.99999936335193)."""
    assert D.f_sf(1e-12, 1, 1) == pytest.approx(1 - 2 * np.arctan(1e-6) / np.pi, rel=1e-15)
    for x in np.concatenate([[0.0, 1e-12, 1e-6], np.geomspace(1e-3, 1e4, 200)]):
        want = stats.f.sf(x, dfn, dfd)
        if want > 1e-300:
            assert D.f_sf(float(x), dfn, dfd) == pytest.approx(want, rel=1e-11, abs=1e-10), (dfn, dfd, x)
    assert D.f_sf(-1.0, dfn, dfd) == 1.0


def test_scalar_in_float_out():
    assert type(D.chi2_sf(3.0, 2)) is float and type(D.beta_ppf(0.5, 2, 3)) is float
    assert D.chi2_sf([1.0, 2.0], 2).shape == (2,)


def test_calibrating_a_recording_imports_no_scipy(tmp_path):
    """`accelcal calibrate` needs the χ² tail at whole degrees of freedom only: importing
    scipy.special would be ~0.25 s, half of its time on the Xsens session."""
    xsens = Path(__file__).resolve().parents[2] / "shared" / "data" / "imu_tk_xsens" / "xsens_acc.mat"
    code = ("import sys\nfrom accelcal import cli\n"
            "try:\n    cli.main()\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.')))\n")
    out = subprocess.run([sys.executable, "-c", code, "calibrate", str(xsens), "--g", "9.81744", "--out",
                          str(tmp_path / "cal.json")], capture_output=True, text=True, timeout=120)
    assert (tmp_path / "cal.json").is_file(), out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout


def test_the_core_library_does_not_import_scipy_stats():
    """The CLI and the discrepancy analysis must not pay scipy.stats' import (or
    scipy.signal's: 1 s each) at import time."""
    code = ("import sys, accelcal.cli, accelcal.discrepancy, accelcal.calibration, accelcal.evaluation; "
            "print(sorted(m for m in ('scipy.stats', 'scipy.signal') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out
