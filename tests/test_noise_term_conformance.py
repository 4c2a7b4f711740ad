"""Every registered noise term passes the same checks (scikit-learn's ``parametrize_with_checks``).

A term's behaviour lives on its entry of :data:`accelcal.noise.terms.TERMS`: its Allan
variance, the grid of its nonlinear parameter, its simulation and the variance of the
difference of two interval means; and what the noise report does with it (its unit, the
correlation of its Allan variances between octaves in the bootstrap, whether the report
fits, plans, exports and warns about it, its Allan-deviation floor).  The checks tie the
behaviours to each other, so an entry whose simulation draws another process than its
Allan variance describes, whose pose-mean variance disagrees with either, whose octave
correlations or Allan-variance slope are not its simulation's or basis's, or which asks
the report for a role outside the IEEE fit, fails.  ``examples/custom_noise_term.py`` adds a
term at run time; ``tests/test_examples.py`` runs these checks on it too.
"""

from __future__ import annotations

import numpy as np
import pytest

from accelcal.discrepancy import stochastic as st
from accelcal.noise import allan as al
from accelcal.noise.allan_fit import octave_correlations
from accelcal.noise.terms import TERMS, IntervalPairs, NoiseModelError, exported_term, ieee_terms, term_parameters

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


def check_report_fields_have_their_types(term):
    assert term.avar_slope is None or isinstance(term.avar_slope, int)
    assert all(isinstance(getattr(term, a), bool) for a in ("ieee", "warn_unresolved"))
    assert all(getattr(term, a) is None or (isinstance(getattr(term, a), str) and getattr(term, a))
               for a in ("planned_as", "exported_as"))
    assert term.floor_factor is None or term.floor_factor > 0
    assert "{u}" in term.unit and "counts" in term.unit_of("counts"), term.unit
    if term.octave_correlation is not None:
        assert len(term.octave_correlation) == 6 and all(-1 <= r <= 1 for r in term.octave_correlation)
    assert -1 <= term.far_correlation <= 1 and (term.far_decay is None or 0 < term.far_decay <= 1)


def check_report_roles_are_terms_the_report_fits(term):
    """Planned, exported, warned about, giving the floor: the report reads these from its IEEE fit,
    which must hold the term, with a power-law slope (the fit's order) and octave correlations
    (its bootstrap)."""
    if term.planned_as or term.exported_as or term.warn_unresolved or term.floor_factor is not None:
        assert term.ieee, "a role in the noise report for a term it does not fit"
    if term.ieee:
        assert term.avar_slope is not None and term.octave_correlation is not None


def check_avar_slope_is_the_basis_slope(term):
    if term.avar_slope is not None:
        _, shape = term_parameters(term.id, term.example)
        tau = np.array([0.5, 1.0, 2.0, 40.0, 80.0])
        b = term.basis(tau, 1e9, shape)
        assert b[2] / b[1] == pytest.approx(2.0**term.avar_slope, rel=1e-9)
        assert b[4] / b[3] == pytest.approx(2.0**term.avar_slope, rel=1e-9)


def check_floor_factor_is_the_flat_allan_deviation(term):
    if term.floor_factor is not None:
        assert term.avar_slope == 0
        assert term.floor_factor == pytest.approx(np.sqrt(term.basis(np.array([1.0]), 100.0)[0]), rel=1e-3)


def check_octave_correlation_is_its_simulations(term):
    """The table against a measurement on its own simulation (records of 2^14 samples, 200 of
    them: the first two octaves to 0.1; the table was measured on 2^16).  A deterministic term
    (the ramp) cannot be measured and borrows another's."""
    if term.octave_correlation is None:
        with pytest.raises(NoiseModelError, match="octave correlations"):
            term.octave_rho(np.arange(3))
        return
    rho = term.octave_rho(np.arange(12))
    assert rho[0] == 1.0 and np.allclose(rho[1:7], term.octave_correlation) and np.all(np.abs(rho) <= 1)
    v, shape = term_parameters(term.id, term.example)
    draws = [term.simulate(v, shape, np.random.default_rng(s), 64, FS, 1) for s in (1, 2)]
    if np.array_equal(*draws):
        return
    measured = octave_correlations(np.random.default_rng(5), term.id, n=2**14, reps=200)
    assert np.allclose(measured[:2], term.octave_correlation[:2], atol=0.1), measured


CHECKS = (check_entry_is_complete, check_allan_basis_is_finite_and_non_negative,
          check_simulation_is_shaped_and_reproducible, check_simulation_has_its_allan_variance,
          check_adjacent_pose_difference_is_twice_the_allan_variance, check_pose_mean_scatter_matches_the_simulation,
          check_white_level_is_what_long_means_see, check_report_fields_have_their_types,
          check_report_roles_are_terms_the_report_fits, check_avar_slope_is_the_basis_slope,
          check_floor_factor_is_the_flat_allan_deviation, check_octave_correlation_is_its_simulations)


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


def test_the_table_gives_the_noise_report_what_it_reads():
    """One term per exported value, one floor, IEEE terms in a defined order (distinct slopes)."""
    assert {exported_term(k).id for k in ("noise_density", "random_walk")} <= set(ieee_terms())
    slopes = [TERMS[k].avar_slope for k in ieee_terms()]
    assert slopes == sorted(slopes) and len(set(slopes)) == len(slopes)
    assert sum(TERMS[k].floor_factor is not None for k in ieee_terms()) == 1


class _WhiteWithTheWalksCorrelations(type(TERMS["white"])):
    octave_correlation = TERMS["random_walk"].octave_correlation


class _RampWithTheWalksSlope(type(TERMS["drift_ramp"])):
    avar_slope = 1


class _GMExported(type(TERMS["gauss_markov"])):
    exported_as = "random_walk"


@pytest.mark.parametrize("planted, check", [
    (_WhiteWithTheWalksCorrelations, check_octave_correlation_is_its_simulations),
    (_RampWithTheWalksSlope, check_avar_slope_is_the_basis_slope),
    (_GMExported, check_report_roles_are_terms_the_report_fits)], ids=["correlations", "slope", "role"])
def test_the_checks_catch_a_wrong_report_field(planted, check):
    with pytest.raises(AssertionError):
        check(planted())
