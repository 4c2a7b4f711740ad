"""Every member of the wander's REML grid passes the same checks (scikit-learn's ``parametrize_with_checks``).

A member's numerics live on its entry of :data:`accelcal.discrepancy.wander.MEMBERS`: its
codes on the grid, its kernel (the variogram of its interval means), its size and
random-walk coefficient, its Allan variance within the rests.  The checks tie the kernel
to the covariance its process states (:data:`accelcal.discrepancy.wander_process.PROCESSES`,
from the noise library where the process is a time series), to the rests' Allan variance,
to the stack the likelihood diagonalises, and to what a variogram must be.
``examples/custom_grid_member.py`` adds a member at run time; ``tests/test_examples.py``
runs these checks on it too.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.discrepancy import wander as C
from accelcal.discrepancy.wander.members import PerPlacement
from accelcal.discrepancy.wander.problem import kernel_eigensystems
from accelcal.discrepancy.wander_process import PROCESSES, process_of
from accelcal.errors import AccelcalError

from .test_wander_process_conformance import DURATIONS, SPAN, STARTS, fit_of

E_X = np.tile([1.0, 0.0, 0.0], (len(STARTS), 1))
Q_ABS = 4e-6


def grid() -> np.ndarray:
    """A session's grid of every member registered now."""
    return C.tau_grid(DURATIONS, SPAN)


def codes_of(member) -> np.ndarray:
    """Up to three of the member's codes on a session's grid (its first, middle and last)."""
    codes = grid()[member.owns(grid())]
    return codes[[0, len(codes) // 2, -1]] if codes.size > 2 else codes


def check_entry_is_complete(member):
    assert isinstance(member.id, str) and member.id and C.MEMBERS[member.id] is member
    assert isinstance(member.size_kind, str) and isinstance(member.tau_note, str)
    assert isinstance(member.region_note, str)
    codes = grid()[member.owns(grid())]
    assert codes.size >= 1, "the member has no code on the grid"
    for code in codes:  # each code is this member's alone
        assert [m.id for m in C.MEMBERS.values() if m.owns(np.array([code]))[0]] == [member.id]
        assert C.member_of(code) is member


def check_kernel_is_its_process_covariance(member):
    """``−2 q_abs × kernel`` is ``D`` of the process the estimate is named (its stated covariance)."""
    for code in codes_of(member):
        w = fit_of(float(code), Q_ABS)
        proc = process_of(w, SPAN)
        assert proc.member == member.id, (code, proc.id)
        D = proc.difference_variance(w, STARTS, DURATIONS)
        kernel = C.wander_kernel(float(code), STARTS, DURATIONS, E_X)
        np.testing.assert_allclose(D, -2.0 * Q_ABS * kernel, rtol=1e-9, atol=1e-15 * Q_ABS, err_msg=str(code))


def check_kernel_is_a_variogram(member):
    """Symmetric, zero on the diagonal, non-negative, and ``−D/2`` positive semi-definite on
    contrasts (a generalised covariance)."""
    n = len(STARTS)
    P = np.eye(n) - 1.0 / n
    for code in codes_of(member):
        D = -2.0 * C.wander_kernel(float(code), STARTS, DURATIONS, E_X)
        assert np.allclose(D, D.T) and np.all(np.diag(D) == 0.0) and np.all(D >= -1e-12 * np.abs(D).max())
        ev = np.linalg.eigvalsh(-0.5 * P @ D @ P)
        assert ev.min() >= -1e-9 * max(ev.max(), 1e-300), (code, ev)
        assert np.abs(D).max() > 0


def check_rest_avar_is_half_the_adjacent_difference(member):
    """Its Allan variance at τ = T is half ``D`` between two adjacent rests of length T (the
    Allan variance's definition), or 0 for a member constant within each rest."""
    T = 4.0
    for code in codes_of(member):
        D = -2.0 * C.wander_kernel(float(code), np.array([0.0, T]), np.array([T, T]), E_X[:2])
        avar = member.rest_avar(float(code), np.array([T]), 1e9)
        assert avar.shape == (1,) and D[0, 1] > 0
        expected = 0.5 * D[0, 1] if member.within_rest else 0.0
        assert avar[0] == pytest.approx(expected, rel=1e-5, abs=1e-12 * D[0, 1]), code


def check_size_and_K_agree(member):
    """The scalar ``(size, K)`` of an estimate is the member's vectorised ``K`` and its size
    rule, and ``K`` is its kernel's short-lag random-walk coefficient: two means of short
    intervals ``h`` apart (``h`` a thousandth of τ) differ with variance ``≈ K² h``."""
    for code in codes_of(member):
        size, K = C.gm_variance(Q_ABS, float(code))
        assert size == (math.sqrt(Q_ABS) if member.stationary else math.inf)
        assert C.gm_variance(0.0, float(code))[0] == 0.0
        if not member.timed:
            assert math.isnan(K)
            continue
        assert K == pytest.approx(float(member.K(np.array([Q_ABS]), np.array([code]))[0]), rel=1e-15) and K > 0
        h = 1e-3 * (float(code) if np.isfinite(code) else 1.0)
        eps = 1e-2 * h  # the intervals' length: a random walk's means differ by K² (h + 2 eps/3)
        D = -2.0 * Q_ABS * C.wander_kernel(float(code), np.array([0.0, eps + h]), np.array([eps, eps]), E_X[:2])
        assert D[0, 1] == pytest.approx(K ** 2 * (h + 2 * eps / 3), rel=2e-3), code


def check_the_likelihoods_stack_is_its_kernel(member):
    """The eigensystem the likelihood uses at each of its columns (a grid holding every
    member) is the member's own contrast kernel."""
    rng = np.random.default_rng(3)
    n = 12
    starts, durations = np.cumsum(rng.uniform(6.0, 12.0, n)), rng.uniform(2.0, 5.0, n)
    grad = rng.standard_normal((n, 3))
    J = np.hstack([-grad, rng.standard_normal((n, 2))])
    taus = C.tau_grid(durations, float(starts[-1] + durations[-1] - starts[0]))
    prob = C.problem(rng.standard_normal(n), J, np.full(n, 0.1), grad, starts, durations, taus=taus, common=0.3)
    lam, V, scale = kernel_eigensystems(prob, prob.taus, 0.3)
    for t in np.flatnonzero(member.owns(prob.taus)):
        Kc = (V[t] * (lam[t] * scale[t])) @ V[t].T
        np.testing.assert_allclose(Kc, prob.kernel(float(prob.taus[t])), rtol=1e-8, atol=1e-10 * np.abs(Kc).max())


CHECKS = [check_entry_is_complete, check_kernel_is_its_process_covariance, check_kernel_is_a_variogram,
          check_rest_avar_is_half_the_adjacent_difference, check_size_and_K_agree,
          check_the_likelihoods_stack_is_its_kernel]


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("member", list(C.MEMBERS.values()), ids=lambda m: m.id)
def test_every_member_passes_every_check(member, check):
    check(member)


def test_every_member_is_some_process_and_the_grid_is_the_table():
    assert {p.member for p in PROCESSES.values() if p.member} >= set(C.MEMBERS)
    g = grid()
    assert C.members_in(g) == tuple(C.MEMBERS)
    assert g[0] == C.FLICKER and g[1] == C.PLACEMENT and np.isinf(g[-1])  # the table's order


def test_a_check_fails_on_a_member_whose_kernel_is_not_its_process():
    """The suite can fail: a per-placement offset whose variogram lost its factor 2."""

    class Halved(PerPlacement):
        def variogram(self, taus, starts, durations, gap):
            return 1.0

    C.MEMBERS["per_placement"] = Halved()
    try:
        with pytest.raises(AssertionError):
            check_kernel_is_its_process_covariance(C.MEMBERS["per_placement"])
    finally:
        C.MEMBERS["per_placement"] = PerPlacement()
    check_kernel_is_its_process_covariance(C.MEMBERS["per_placement"])


def test_a_check_fails_on_a_member_with_another_allan_shape():
    """Flicker given a random walk's Allan variance in the rests."""
    flicker = C.MEMBERS["flicker"]
    wrong = SimpleNamespace(within_rest=True, owns=flicker.owns, rest_avar=C.MEMBERS["random_walk"].rest_avar)
    with pytest.raises(AssertionError):
        check_rest_avar_is_half_the_adjacent_difference(wrong)


def test_a_code_is_one_members_and_an_unknown_code_is_refused():
    class Again(PerPlacement):
        id = "another_offset"

    with pytest.raises(AccelcalError, match="already 'per_placement'"):
        C.register_member(Again)
    assert "another_offset" not in C.MEMBERS
    with pytest.raises(AccelcalError, match="no grid member has the code"):
        C.wander_kernels(np.array([-7.0]), STARTS, DURATIONS, E_X)


# --------------------------------------------------------------------------- no branch on a code elsewhere

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "src" / "accelcal" / "discrepancy" / "wander" / "members.py"
CODE_NAMES = {"FLICKER", "PLACEMENT"}


def _names_a_code(node) -> bool:
    """``FLICKER``/``PLACEMENT`` (or ``C.FLICKER``), alone or in a tuple, list or set."""
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(map(_names_a_code, node.elts))
    return isinstance(node, ast.Name | ast.Attribute) and (
        node.id if isinstance(node, ast.Name) else node.attr) in CODE_NAMES


def _is_code_literal(node) -> bool:
    """The literal 0 or −1 (the offset's and flicker's codes)."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return isinstance(node.operand, ast.Constant) and node.operand.value == 1
    return isinstance(node, ast.Constant) and type(node.value) in (int, float) and node.value == 0


def _mentions_tau(node) -> bool:
    """A name or attribute that is a τ of the grid: ``tau``, ``taus``, ``w.tau``, ``tv`` (reml's)."""
    return any("tau" in name or name == "tv" for name in (n.id if isinstance(n, ast.Name) else n.attr
               for n in ast.walk(node) if isinstance(n, ast.Name | ast.Attribute)))


def _branches(node) -> bool:
    if isinstance(node, ast.Compare):
        sides = [node.left, *node.comparators]
        if not all(isinstance(op, ast.Eq | ast.NotEq | ast.In | ast.NotIn) for op in node.ops):
            return False
        return any(map(_names_a_code, sides)) or (
            any(map(_is_code_literal, sides)) and any(_mentions_tau(s) and not _is_code_literal(s) for s in sides))
    if isinstance(node, ast.Call):
        return getattr(node.func, "attr", getattr(node.func, "id", "")) == "isinf" and any(map(_mentions_tau,
                                                                                              node.args))
    return False


def code_branches(path: Path, root: Path = ROOT) -> list[str]:
    """``file:line: source`` of every comparison with a member's code (by name, or a τ with 0
    or −1) and every ``isinf`` of a τ (the random walk's code) in ``path``."""
    return [f"{path.relative_to(root)}:{node.lineno}: {ast.unparse(node)}"
            for node in ast.walk(ast.parse(path.read_text(), filename=str(path))) if _branches(node)]


def test_no_module_branches_on_a_members_code():
    """What a member does is on its entry: no ``tau == FLICKER``, ``tau == 0``, ``np.isinf(tau)``
    in the discrepancy packages outside the table (rests.py, reml.py, problem.py and the
    process table had them)."""
    files = sorted(p for pkg in ("accelcal", "accelcal_repro") for p in (ROOT / "src" / pkg / "discrepancy").rglob("*.py")
                   if p != TABLE)
    assert len(files) > 40
    assert [c for p in files for c in code_branches(p)] == []


def test_the_code_check_sees_the_old_branches(tmp_path):
    old = tmp_path / "old.py"
    old.write_text("def f(tau, taus, w, qv, shortest):\n"
                   "    a = tau == 0.0\n"
                   "    b = taus == FLICKER\n"
                   "    c = np.isinf(w.tau)\n"
                   "    d = tau == -1.0\n"
                   "    e = w.tau == PLACEMENT\n"
                   "    g = tau in (PLACEMENT, FLICKER)\n"
                   "    fine = (tau > 0.5 * shortest, tau > 0, qv == 0, np.isinf(qv))\n")
    found = [line.split(": ", 1)[1] for line in code_branches(old, tmp_path)]
    assert found == ["tau == 0.0", "taus == FLICKER", "np.isinf(w.tau)", "tau == -1.0", "w.tau == PLACEMENT",
                     "tau in (PLACEMENT, FLICKER)"], found
