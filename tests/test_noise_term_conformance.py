"""Every registered noise term passes the same checks (scikit-learn's ``parametrize_with_checks``).

A term's behaviour lives on its entry of :data:`accelcal.noise.terms.TERMS`: its Allan
variance, the grid of its nonlinear parameter, its simulation and the variance of the
difference of two interval means.  The checks tie the behaviours to each other, so an
entry whose simulation draws another process than its Allan variance describes, or whose
pose-mean variance disagrees with either, fails.  ``examples/custom_noise_term.py`` adds a
term at run time; ``tests/test_examples.py`` runs these checks on it too.
"""

from __future__ import annotations

import numpy as np
import pytest

from accelcal.discrepancy import stochastic as st
from accelcal.noise import allan as al
from accelcal.noise.terms import TERMS, IntervalPairs, NoiseModelError, term_parameters

FS = 100.0


def check_entry_is_complete(term):
    for attr in ("id", "symbol", "unit", "meaning", "name", "colour", "label"):
        assert isinstance(getattr(term, attr), str) and getattr(term, attr), attr
    coefficient, shape = term_parameters(term.id, term.example)
    assert coefficient > 0 and (shape is None) == (term.shape_key is None)
    if term.shape_key is None:
        with pytest.raises(NoiseModelError):
            term.shape_grid(FS, 100.0)
    else:
        grid = term.shape_grid(FS, 100.0)
        assert grid.ndim == 1 and grid.size >= 3 and np.all(np.diff(grid) > 0)


def check_allan_basis_is_finite_and_non_negative(term):
    _, shape = term_parameters(term.id, term.example)
    b = term.basis(np.logspace(-2, 2, 30), FS, shape)
    assert b.shape == (30,) and np.all(np.isfinite(b)) and np.all(b >= 0)


def check_simulation_is_shaped_and_reproducible(term):
    v, shape = term_parameters(term.id, term.example)
    one = term.simulate(v, shape, np.random.default_rng(3), 500, FS, 4)
    two = term.simulate(v, shape, np.random.default_rng(3), 500, FS, 4)
    assert one.shape == (500, 4) and np.all(np.isfinite(one)) and np.array_equal(one, two)


def check_simulation_has_its_allan_variance(term):
    v, shape = term_parameters(term.id, term.example)
    rng = np.random.default_rng(30)
    a = al.allan_variance([term.simulate(v, shape, rng, n, FS, 200) for n in [4000] + [600] * 10], FS)
    theory = v**2 * term.basis(a.taus, FS, shape)
    mean, se = a.avar.mean(axis=1), a.avar.std(axis=1, ddof=1) / np.sqrt(a.avar.shape[1])
    # from m = 8 on: the Kasdin flicker (+5 % at m = 4) and the discrete walk (+3 % at m = 4)
    # have converged to the continuous forms
    ok = np.abs(mean - theory) <= 4 * se + 0.02 * theory
    assert np.all(ok[3:]), mean / np.where(theory > 0, theory, np.nan)


def check_adjacent_pose_difference_is_twice_the_allan_variance(term):
    v, shape = term_parameters(term.id, term.example)
    T = 1.3
    D = term.interval_difference_variance(v**2, shape, IntervalPairs(np.array([0.0, T]), np.array([T, T])))
    assert D[0, 1] == pytest.approx(2 * v**2 * term.basis(np.array([T]), 1e9, shape)[0], rel=1e-6, abs=1e-12)


def check_pose_mean_scatter_matches_the_simulation(term):
    """Scatter of simulated pose means about their common mean = the closed form (within 4 s.e.)."""
    fs = 20.0
    starts, durations = np.array([0.0, 12.0, 30.0, 41.0, 70.0]), np.array([8.0, 5.0, 6.0, 9.0, 4.0])
    n = int((starts + durations).max() * fs) + 1
    v, shape = term_parameters(term.id, term.example)
    white = TERMS["white"]
    burn = 2 * n  # the Kasdin flicker starts from rest and lacks low frequencies near its start
    rng = np.random.default_rng(7)
    # white noise keeps every pose's variance above zero
    x = (term.simulate(v, shape, rng, burn + n, fs, 2000) + white.simulate(0.1, None, rng, burn + n, fs, 2000))[burn:]
    means = np.stack([x[int(a * fs):int(a * fs) + int(T * fs)].mean(axis=0) for a, T in zip(starts, durations)])
    centred = means - means.mean(axis=0)
    mc, mc_se = (centred**2).mean(axis=1), (centred**2).std(axis=1) / np.sqrt(centred.shape[1])
    iv = IntervalPairs(starts, durations)
    D = term.interval_difference_variance(v**2, shape, iv) + white.interval_difference_variance(0.01, None, iv)
    np.fill_diagonal(D, 0.0)
    pred = st.centred_pose_variance(D)
    assert np.all(np.abs(mc - pred) < 4 * mc_se + 0.05 * pred), (mc, pred)


def check_white_level_is_what_long_means_see(term):
    """Where a term says it acts as white noise (``white_level``: ``N²``), the means of two
    adjacent intervals far longer than its time scale differ as white noise's do, ``2 N²/T``."""
    v, shape = term_parameters(term.id, term.example)
    T = 1e3 * (shape or 1.0)
    n2 = term.white_level(term.example, T)
    assert n2 is None or n2 > 0
    if n2 is not None:
        D = term.interval_difference_variance(v**2, shape, IntervalPairs(np.array([0.0, T]), np.array([T, T])))
        assert D[0, 1] == pytest.approx(2 * n2 / T, rel=0.01)


CHECKS = (check_entry_is_complete, check_allan_basis_is_finite_and_non_negative,
          check_simulation_is_shaped_and_reproducible, check_simulation_has_its_allan_variance,
          check_adjacent_pose_difference_is_twice_the_allan_variance, check_pose_mean_scatter_matches_the_simulation,
          check_white_level_is_what_long_means_see)


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
@pytest.mark.parametrize("term_id", list(TERMS))
def test_every_noise_term_passes_every_check(term_id, check):
    check(TERMS[term_id])


class _SimulatesTheWrongProcess(type(TERMS["random_walk"])):
    """A random walk whose simulation draws white noise: the checks must catch it."""

    def simulate(self, v, shape, rng, n, fs, cols):
        return TERMS["white"].simulate(v, shape, rng, n, fs, cols)


def test_the_checks_catch_an_entry_whose_simulation_is_another_process():
    with pytest.raises(AssertionError):
        check_simulation_has_its_allan_variance(_SimulatesTheWrongProcess())
