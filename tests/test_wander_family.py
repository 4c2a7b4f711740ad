"""The wander null's family (issue 34 item 1): the flicker member and the rests' likelihood.

Each test can fail: the flicker member's kernel is checked against the noise library's
closed form, the rests' Allan variances against the simulated truth, the joint
likelihood's choice against the member that made the samples, and the old family
against ever choosing the new member.
"""

import dataclasses

import numpy as np
import pytest

from accelcal.discrepancy import wander as C
from accelcal.discrepancy.fit import fit
from accelcal.discrepancy.rules import WANDER_FAMILIES, Rules
from accelcal.discrepancy.stochastic.implication import pose_difference_variance
from accelcal.discrepancy.wander.rests import RestAllan, rest_allan, rest_deviance
from accelcal.discrepancy.wander_model import linearise_noise
from accelcal.discrepancy.wander_process import FAMILIES
from accelcal.errors import AccelcalError
from accelcal.noise import simulate_noise
from tests.wander_sessions import rest_session

FS = 100.0


def _rests(n_rests=30, rest_s=5.5, gap_s=2.5):
    """Sample intervals of ``n_rests`` rests of ``rest_s`` seconds with ``gap_s`` between them."""
    a = np.arange(n_rests) * int((rest_s + gap_s) * FS)
    return np.column_stack([a, a + int(rest_s * FS)])


def test_flicker_member_is_the_noise_librarys_flicker():
    starts, durations = np.array([0.0, 8.0, 30.0, 31.0]), np.array([5.5, 5.5, 0.5, 20.0])
    D = C.wander_kernels(np.array([C.FLICKER]), starts, durations, np.eye(4, 3))[0]
    ref = pose_difference_variance("bias_instability", 1.0, starts, durations)
    G = np.eye(4, 3) @ np.eye(3, 4)
    assert np.allclose(D, -0.5 * G * ref)
    grid = C.tau_grid(durations, 60.0)
    assert grid[0] == C.FLICKER and grid[1] == C.PLACEMENT and np.isinf(grid[-1])
    assert C.FLICKER not in C.tau_grid(durations, 60.0, members=FAMILIES["one_process"].members)


def test_rest_allan_gives_white_then_the_flicker_floor():
    rng = np.random.default_rng(3)
    iv = _rests()
    n = int(iv[-1, 1])
    white = simulate_noise(rng, n, FS, {"white": 0.33}, size=3)    # 3.3 counts per sample
    ra = rest_allan(white, iv, FS)
    assert ra.taus[0] >= 0.1 * 5.5       # only octaves near the poses' time scales
    # white noise: m Â(m) stays at the per-sample variance within the rests' precision
    rel = ra.avar * ra.m[None] / (3.3 ** 2)
    assert np.all(np.abs(rel - 1) < 4 * np.sqrt(2.0 / ra.dof)), rel
    B = 1.0
    fl = white + simulate_noise(rng, n, FS, {"bias_instability": B}, size=3)
    rf = rest_allan(fl, iv, FS)
    floor = 2 * np.log(2) / np.pi * B ** 2
    # at the longest octaves the floor dominates white noise: their excess is the floor
    k = rf.taus >= 0.5
    excess = rf.avar[:, k].mean(axis=0) - 3.3 ** 2 / rf.m[k]
    assert np.all(np.abs(excess / floor - 1) < 0.5), excess / floor


def test_rests_likelihood_tells_flicker_from_a_random_walk():
    """Samples with a flicker floor: the rests' deviance at the flicker member of the true
    size is far below that of no wander, and below a random walk of the same pose-to-pose size."""
    rng = np.random.default_rng(4)
    iv = _rests()
    n = int(iv[-1, 1])
    B = 1.0
    x = simulate_noise(rng, n, FS, {"white": 0.33, "bias_instability": B}, size=3)
    ra = rest_allan(x, iv, FS)
    fl = rest_deviance(ra, B ** 2 * ra.member_avar(C.FLICKER))
    none = rest_deviance(ra, 0.0 * ra.member_avar(C.FLICKER))
    # a random walk whose 8 s pose-to-pose variance matches the flicker's: K² 8/3 ≈ 2 ln2/π · 2 B²
    K2 = 2 * np.log(2) / np.pi * 2 * B ** 2 * 3 / 8
    rw = rest_deviance(ra, K2 * ra.member_avar(np.inf))
    # (the octaves near the poses' scales only: the random walk is less far than over every octave)
    assert none - fl > 20 and rw - fl > 5, (fl, none, rw)
    # and white samples do not prefer the flicker floor
    w = rest_allan(simulate_noise(rng, n, FS, {"white": 0.33}, size=3), iv, FS)
    assert rest_deviance(w, 0.0 * w.m) < rest_deviance(w, B ** 2 * w.member_avar(C.FLICKER))


def test_deviance_grid_is_zero_at_its_minimum_and_cached():
    ra = rest_allan(np.random.default_rng(5).standard_normal((int(_rests()[-1, 1]), 3)), _rests(), FS)
    taus = np.array([C.FLICKER, C.PLACEMENT, 3.0, np.inf])
    g = ra.deviance_grid(taus, np.ones(4), C.Q_REL_GRID)
    assert g.shape == (4, C.Q_REL_GRID.size) and g.min() == 0.0 and np.all(np.isfinite(g))
    assert ra.deviance_grid(taus, np.ones(4), C.Q_REL_GRID) is g
    # the per-placement offset is invisible in the rests: flat in q
    assert np.ptp(g[1]) == 0.0


def test_too_short_rests_give_no_statistic():
    assert rest_allan(np.zeros((10, 3)), np.array([[0, 3]]), FS) is None


def test_wander_family_is_checked_and_the_old_one_stays_selectable():
    with pytest.raises(AccelcalError, match="wander_family"):
        Rules(wander_family="two_gm")
    assert set(WANDER_FAMILIES) == {"one_process", "flicker", "flicker_rests", "sum"}
    assert dataclasses.replace(Rules(), wander_family="one_process").wander_family == "one_process"
    assert isinstance(rest_allan(np.ones((400, 3)), np.array([[0, 400]]), FS), RestAllan)


def test_joint_likelihood_names_the_flicker_member_the_pose_means_alone_cannot():
    """A flicker wander 3 pose-mean sigmas strong: with the rests the joint REML chooses the
    flicker member on most sessions; from the pose means alone it does so far less often
    (and never in the old family, which lacks it)."""
    rng = np.random.default_rng(11)
    chosen = {"one_process": [], "flicker": [], "flicker_rests": []}
    for _ in range(4):
        data, _, _ = rest_session(rng, {"white": 0.33, "bias_instability": 3 * 0.141 / 0.664}, sample_sd=3.3)
        f = fit(data)
        for fam in chosen:
            w = linearise_noise(data, f, fam)[2]
            chosen[fam].append(bool(w.present and w.member is C.MEMBERS["flicker"]))
    assert not any(chosen["one_process"]), chosen
    assert sum(chosen["flicker_rests"]) >= 3 and sum(chosen["flicker_rests"]) > sum(chosen["flicker"]), chosen
