"""Every estimator rejects bad pose sets with a typed, one-line error."""

import numpy as np
import pytest

from accelcal import (
    DegeneratePosesError,
    InputShapeError,
    NonFiniteError,
    NotPositiveDefiniteError,
    TooFewPosesError,
    bias_lls,
    bias_nlls,
    full_als,
    full_lls,
    full_lls_batch,
    full_nlls,
)

from .conftest import G, make_poses
from .test_estimators import _hyperboloid_points

FULL = [full_lls, full_nlls, full_als]
BIAS = [bias_lls, bias_nlls]
ALL = FULL + BIAS


def _one_line(exc):
    msg = str(exc.value)
    assert msg and "\n" not in msg and "Traceback" not in msg


@pytest.mark.parametrize("est", FULL)
def test_full_models_need_ten_poses(rng, truth, est):
    with pytest.raises(TooFewPosesError, match="at least 10") as e:
        est(make_poses(rng, truth, 9, 1e-4), G)
    _one_line(e)


@pytest.mark.parametrize("est", BIAS)
def test_bias_models_need_four_poses(rng, truth, est):
    with pytest.raises(TooFewPosesError, match="at least 4"):
        est(make_poses(rng, truth, 3, 1e-4), G)


@pytest.mark.parametrize("est", ALL)
def test_coplanar_poses(rng, truth, est):
    a = rng.uniform(0, 2 * np.pi, 24)
    u = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])  # turned about z only
    z = G * u + truth["bias"] + rng.normal(0, 1e-4, u.shape)
    with pytest.raises(DegeneratePosesError, match="one plane") as e:
        est(z, G)
    _one_line(e)


@pytest.mark.parametrize("est", ALL)
def test_one_axis_only(rng, truth, est):
    u = np.repeat([[0, 0, 1.0], [0, 0, -1.0]], 12, axis=0)
    z = G * u + truth["bias"] + rng.normal(0, 1e-4, u.shape)
    with pytest.raises(DegeneratePosesError, match="one axis"):
        est(z, G)


@pytest.mark.parametrize("est", ALL)
def test_identical_poses(truth, est):
    z = np.tile(G * np.array([0, 0, 1.0]) + truth["bias"], (24, 1))
    with pytest.raises(DegeneratePosesError, match="never turned"):
        est(z, G)


def test_two_planes_do_not_determine_the_full_model(rng, truth):
    """Poses on two great circles lie on a degenerate quadric: the null space is 2-D."""
    a = rng.uniform(0, 2 * np.pi, 12)
    u = np.vstack([np.column_stack([np.cos(a), np.sin(a), 0 * a]),
                   np.column_stack([np.cos(a), 0 * a, np.sin(a)])])
    z = G * u + truth["bias"]
    with pytest.raises(DegeneratePosesError, match="does not determine"):
        full_lls(z, G)
    bias_lls(z, G)  # ... while three unknowns are still determined


@pytest.mark.parametrize("est", ALL)
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite(rng, truth, est, bad):
    z = make_poses(rng, truth, 24, 1e-4)
    z[3, 1] = bad
    with pytest.raises(NonFiniteError):
        est(z, G)


@pytest.mark.parametrize("est", ALL)
@pytest.mark.parametrize("shape", [(24,), (24, 2), (24, 4), (2, 24, 3)])
def test_wrong_shape(est, shape):
    with pytest.raises(InputShapeError, match="shape"):
        est(np.ones(shape), G)


@pytest.mark.parametrize("est", ALL)
@pytest.mark.parametrize("g", [0.0, -9.8, np.nan])
def test_bad_g(rng, truth, est, g):
    with pytest.raises(InputShapeError, match="g must be"):
        est(make_poses(rng, truth, 24, 1e-4), g)


@pytest.mark.parametrize("est", [full_lls, full_als])
def test_not_an_ellipsoid(rng, est):
    with pytest.raises(NotPositiveDefiniteError, match="positive definite") as e:
        est(_hyperboloid_points(rng, 24), G)
    _one_line(e)


def test_batch_wrong_shape_and_nan(rng, truth):
    with pytest.raises(InputShapeError):
        full_lls_batch(make_poses(rng, truth, 24, 1e-4), G)
    Z = make_poses(rng, truth, 24, 1e-4)[None].copy()
    Z[0, 0, 0] = np.nan
    with pytest.raises(NonFiniteError):
        full_lls_batch(Z, G)
