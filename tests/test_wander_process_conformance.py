"""Every registered wander process passes the same checks (scikit-learn's ``parametrize_with_checks``).

A process's behaviour lives on its entry of
:data:`accelcal.discrepancy.wander_process.PROCESSES`: which REML estimate it is, its
covariance between pose means, what it adds to the rests' Allan variance, the noise-library
terms the reproductions simulate it with, its JSON names and its reading.  The checks tie
these to each other and to the REML grid's own kernel (:func:`accelcal.discrepancy.wander.wander_kernel`),
so an entry whose simulation, covariance or Allan shape describe different processes fails.
``examples/custom_wander_process.py`` adds a process at run time; ``tests/test_examples.py``
runs these checks on it too.
"""

from __future__ import annotations

import json
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.discrepancy import wander as C
from accelcal.discrepancy.schema import STATUS, check_statuses
from accelcal.discrepancy.stochastic import pose_difference_variance
from accelcal.discrepancy.wander_model import describe_noise_model, noise_model_dict
from accelcal.discrepancy.rules import WANDER_FAMILIES
from accelcal.discrepancy.wander_process import FAMILIES, PROCESSES, process_in, process_of
from accelcal.jsonsafe import json_safe
from accelcal.noise.terms import TERMS

STARTS, DURATIONS = np.array([0.0, 12.0, 30.0, 41.0, 70.0]), np.array([8.0, 5.0, 6.0, 9.0, 4.0])
SPAN = float((STARTS + DURATIONS).max() - STARTS.min())
NM_KEYS = set(noise_model_dict(None, None, "x")) | {"size", "size_ci", "tau_s", "tau_ci", "random_walk_K",
                                                    "random_walk_K_ci", "change_over_session", "session_s"}


def fit_of(tau: float, q_abs: float, **fields) -> C.WanderFit:
    """A REML estimate of the member ``tau`` of the grid with wander variance ``q_abs``."""
    size, K = C.gm_variance(q_abs, tau)
    w = C.WanderFit(t=0, q_rel=1.0 if q_abs > 0 else 0.0, tau=tau, q_abs=q_abs, size=size, K=K,
                    white_scale=1.2, reml=0.0, size_ci=(0.5 * size, 2 * size), tau_ci=(0.5 * tau, 2 * tau),
                    K_ci=(0.5 * K, 2 * K), white_scale_ci=(0.9, 1.5), excess_ci=(1.0, 1.3), at_bound=(),
                    common=0.2, common_ci=(0.0, 0.5))
    return replace(w, **fields)


def noise_model_of(w: C.WanderFit) -> dict:
    prob = SimpleNamespace(durations=DURATIONS, span=SPAN, notes=())
    return noise_model_dict(w, prob)


def check_entry_is_complete(proc):
    for attr in ("id", "term", "meaning", "label"):
        assert isinstance(getattr(proc, attr), str) and getattr(proc, attr), attr
    assert proc.id in STATUS["noise_model.process"] and proc.term in STATUS["noise_model.term"]
    assert proc.noise_term is None or proc.noise_term in TERMS
    assert set(proc.parameters) <= NM_KEYS, set(proc.parameters) - NM_KEYS
    assert PROCESSES[proc.id] is proc


def check_the_estimate_is_named_this_process(proc):
    w = fit_of(**proc.example)
    assert process_of(w, SPAN) is proc
    nm = noise_model_of(w)
    assert nm["process"] == proc.id and nm["term"] == proc.term
    check_statuses({"noise_model": json_safe(nm)})


def check_difference_variance_is_the_reml_kernel(proc):
    """``D`` of the entry = that of the grid member the REML fitted (one axis, gradient e_x)."""
    tau, q_abs = proc.example["tau"], proc.example["q_abs"]
    grad = np.tile([1.0, 0.0, 0.0], (len(STARTS), 1))
    D = proc.difference_variance(fit_of(**proc.example), STARTS, DURATIONS)
    kernel = C.wander_kernel(tau, STARTS, DURATIONS, grad)
    np.testing.assert_allclose(D, -2.0 * q_abs * kernel, rtol=1e-9, atol=1e-15 * q_abs)


def check_json_reads_back_the_same(proc):
    """The report's JSON names the same process and reads the same as the result in memory."""
    nm = noise_model_of(fit_of(**proc.example))
    back = json.loads(json.dumps(json_safe(nm)))
    assert process_in(back) is proc
    assert describe_noise_model(back, "m/s^2") == describe_noise_model(nm, "m/s^2")
    assert back["reading"] == nm["reading"] and nm["reading"]
    value, ci = proc.cell(back, lambda v: "open" if v is None else f"{float(v):.3g}")
    assert value and ci
    assert (proc.size(back) is not None) == ("size" in proc.parameters)


def check_components_simulate_its_covariance(proc):
    """The noise-library terms the reproductions simulate it with (``components``, plus a
    per-placement offset) have the fitted estimate's covariance between pose means."""
    w = fit_of(**proc.example)
    nm = json.loads(json.dumps(json_safe(noise_model_of(w))))
    D = sum((pose_difference_variance(term, value, STARTS, DURATIONS) for term, value in proc.components(nm)),
            np.zeros((len(STARTS),) * 2))
    D = D + 2.0 * proc.placement_size(nm) ** 2 * (1.0 - np.eye(len(STARTS)))
    assert all(term == proc.noise_term for term, _ in proc.components(nm))
    assert proc.placement_size(nm) ** 2 == pytest.approx(proc.own_variance(w), rel=1e-9)
    np.testing.assert_allclose(D, proc.difference_variance(w, STARTS, DURATIONS), rtol=1e-6, atol=1e-15)


def check_rest_allan_is_half_the_adjacent_difference(proc):
    """What it adds to the rests' Allan variance at τ = T is half the variance between the
    means of two adjacent rests of length T (the definition of the Allan variance)."""
    w = fit_of(**proc.example)
    nm = json.loads(json.dumps(json_safe(noise_model_of(w))))
    found = proc.rest_allan(nm)
    T = 4.0
    D = proc.difference_variance(w, np.array([0.0, T]), np.array([T, T]))
    if isinstance(found, dict):  # the rests cannot show it: constant within each rest
        assert found["verdict"] and proc.noise_term is None and D[0, 1] > 0
        return
    k, k_ci, avar = found
    assert len(k_ci) == 2 and k_ci[0] <= k <= k_ci[1]
    assert avar(np.array([T]), k, 1e9)[0] == pytest.approx(0.5 * D[0, 1], rel=1e-5)


CHECKS = [check_entry_is_complete, check_the_estimate_is_named_this_process,
          check_difference_variance_is_the_reml_kernel, check_json_reads_back_the_same,
          check_components_simulate_its_covariance, check_rest_allan_is_half_the_adjacent_difference]
ESTIMATED = [p for p in PROCESSES.values() if p.example is not None]


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("proc", ESTIMATED, ids=lambda p: p.id)
def test_every_process_passes_every_check(proc, check):
    check(proc)


def test_no_wander_is_named_without_one_and_reads_as_such():
    w = fit_of(30.0, 0.0)
    none = process_of(w, SPAN)
    assert none.example is None and none.components({}) == () and none.placement_size({}) == 0.0
    nm = noise_model_of(w)
    assert nm["process"] == none.id and nm["term"] == none.id and "no pose-to-pose noise" in nm["reading"]
    assert none.rest_allan(nm) == {"verdict": "no wander named"}


def test_every_process_of_the_schema_is_registered():
    assert set(STATUS["noise_model.process"]) == set(PROCESSES)
    assert len(ESTIMATED) >= 4


def test_a_report_without_the_process_key_is_read_by_its_term():
    """Reports from before the ``process`` key named the term only."""
    assert process_in({"term": "per_placement_offset"}).id == "per_placement"
    assert process_in({"term": "bias_wander", "tau_s": 120.0}).id == "gauss_markov"
    assert process_in({"term": "bias_wander", "tau_s": None}).id == "random_walk"
    assert process_in({"term": "not_estimated"}).id == "none"
    assert process_in({"estimated": False, "process": "white per-pose noise times a common scale"}).id == "none"
    with pytest.raises(Exception, match="not registered"):
        process_in({"estimated": True, "process": "telegraph"})


def test_a_check_fails_on_an_entry_whose_simulation_differs():
    """The suite can fail: a Gauss–Markov entry simulated at twice its correlation time."""
    gm = PROCESSES["gauss_markov"]
    wrong = SimpleNamespace(**{k: getattr(gm, k) for k in ("id", "noise_term", "example", "difference_variance",
                                                            "placement_size", "own_variance")},
                            components=lambda nm: ((gm.noise_term, (float(nm["size"]), 2 * float(nm["tau_s"]))),))
    with pytest.raises(AssertionError):
        check_components_simulate_its_covariance(wrong)


@pytest.mark.parametrize("family", FAMILIES.values(), ids=lambda f: f.id)
def test_every_family_says_what_its_grid_holds(family):
    """The family's entry is what the wander's grid and problem are built from."""
    assert family.meaning and family.id in WANDER_FAMILIES
    grid = C.tau_grid(DURATIONS, SPAN, members=family.members)
    assert C.members_in(grid) == family.grid_members() and set(family.grid_members()) <= set(C.MEMBERS)
    assert (C.FLICKER in grid) == ("flicker" in family.grid_members()) and C.PLACEMENT in grid
    assert np.isinf(grid).any()
