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


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
@pytest.mark.parametrize("est", ALL)
def test_values_whose_squares_overflow(rng, truth, est):
    with pytest.raises(NonFiniteError, match="too large") as e:
        est(make_poses(rng, truth, 24, 1e-4) * 1e160, G)
    _one_line(e)


@pytest.mark.parametrize("est", ALL)
def test_non_finite_takes_precedence_over_too_few_poses(rng, truth, est):
    z = make_poses(rng, truth, 3, 1e-4)
    z[0, 0] = np.nan
    with pytest.raises(NonFiniteError):
        est(z, G)


def _bad_pose_sets(rng, truth):
    a = rng.uniform(0, 2 * np.pi, 24)
    circle = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])
    b = rng.uniform(0, 2 * np.pi, 12)
    two_planes = np.vstack([np.column_stack([np.cos(b), np.sin(b), 0 * b]), np.column_stack([np.cos(b), 0 * b, np.sin(b)])])
    nan = make_poses(rng, truth, 24, 1e-4)
    nan[5, 2] = np.nan
    return {
        "coplanar": G * circle + truth["bias"] + rng.normal(0, 1e-4, circle.shape),
        # out of plane by ±0.039: scatter eigenvalue 1.5e-3 of the trace, between COPLANAR_TOL
        # and the margin of the moment check, so the reference check decides
        "just_out_of_plane": G * (circle + np.outer((-1) ** np.arange(24), [0, 0, 0.039])) + truth["bias"],
        "one_axis": G * np.repeat([[0, 0, 1.0], [0, 0, -1.0]], 12, axis=0) + truth["bias"],
        "identical": np.tile(G * np.array([0, 0, 1.0]) + truth["bias"], (24, 1)),
        "nearly_identical": G * np.array([0, 0, 1.0]) + rng.normal(0, 1e-9, (24, 3)),
        "two_planes": G * two_planes + truth["bias"],
        "hyperboloid": _hyperboloid_points(rng, 24),
        "nan": nan,
        "zeros": np.zeros((24, 3)),
    }


def test_fast_routes_raise_exactly_what_the_references_raise(rng, truth):
    """The single-problem fast routes decide nothing themselves in doubtful cases: they
    hand over to the reference implementations, so the errors are identical."""
    from accelcal import lls

    for name, z in _bad_pose_sets(rng, truth).items():
        for fast, ref in ((lls.full_lls, lls._full_lls_svd), (lls.bias_lls, lls._bias_lls_lstsq)):
            outcome = []
            for f in (fast, ref):
                try:
                    f(z, G)
                    outcome.append(None)
                except Exception as exc:  # noqa: BLE001 - comparing whatever is raised
                    outcome.append((type(exc), str(exc)))
            assert outcome[0] == outcome[1], (name, fast.__name__, outcome)
