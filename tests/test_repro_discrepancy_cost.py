"""The benchmark's cheaper paths give the same decisions: the wander loop's decisions-only
mode (no fits of candidates that cannot pass) and the stacked refits of the bootstrap,
compiled and in numpy."""

import numpy as np
import pytest

from accelcal import kernels

from accelcal.discrepancy import rules as D
from accelcal.discrepancy.detect import discrepancy
from accelcal.discrepancy.fit import pose_data_from_static
from accelcal.discrepancy.wander import Q_REL_GRID, basis, profile
from accelcal.discrepancy.wander.gls import grid_logdet, grid_ml_min
from accelcal.discrepancy.wander_model import linearise_noise
from accelcal.static import detect_static_recording
from accelcal_repro.discrepancy import benchmark as B
from accelcal_repro.discrepancy import profiles as P

SESSION = B.Session()
RULES = D.Rules()
GM = P.build_profiles([{"name": "gm_3x_session", "gauss_markov": [[3.0, "session"]]}], SESSION)["gm_3x_session"]


def _data(truth="quadratic", size=3.0, replicate=0):
    rec, _ = B.simulate_case(truth, size, replicate, seed=5, session=SESSION, rules=RULES, profile=GM)
    return pose_data_from_static(detect_static_recording(rec), SESSION.g)


def test_decisions_only_mode_decides_as_the_report():
    data = _data()
    full, fast = discrepancy(data, RULES, report=True), discrepancy(data, RULES, report=False)
    assert full.effects == fast.effects == ("quadratic",)
    keys = ("effect", "round", "identifiable", "p_value", "p_adjusted", "passed", "named", "delta_bic",
            "confounded_with_wander")
    assert [[getattr(c, k) for k in keys] for c in full.candidates] == [[getattr(c, k) for k in keys]
                                                                        for c in fast.candidates]
    skipped = [c for c in fast.candidates if c.identifiable and c.p_adjusted > RULES.alpha]
    assert skipped and all(np.isnan(c.estimate).all() and np.isnan(c.lopo_gap) for c in skipped)
    assert all(np.isfinite(c.estimate).all() for c in full.candidates if c.identifiable)


@pytest.mark.parametrize("backend", ["numba", "numpy"])
def test_stacked_refits_equal_one_profile_per_model(backend):
    data = _data("none", 0.0, 1)
    prob, bas0, _ = linearise_noise(data, discrepancy(data, RULES, report=False).base)
    rng = np.random.default_rng(3)
    # data sets of every size: the white scale inside its range and at both of its ends
    cols = [rng.standard_normal((prob.m, 3)) for _ in range(3)]
    bases = [basis(prob, np.hstack([prob.X0, c])) for c in cols]
    Y = rng.standard_normal((9, prob.m)) * np.array([1.0] * 5 + [0.3, 0.1, 3.0, 10.0])[:, None]
    one = np.array([profile(prob, np.hstack([prob.X0, c]), Y, Q_REL_GRID, bas=b).ml_min()
                    for c, b in zip(cols, bases)])
    previous = kernels.set_backend(backend)
    try:
        stacked = grid_ml_min(bases, Y, grid_logdet(prob), prob.m)
    finally:
        kernels.set_backend(previous)
    assert np.allclose(stacked, one, rtol=1e-12, atol=1e-9)
