"""Adding a member to the wander's REML grid: its kernel on one class, its name on another.

The member: a bias that drifts at a constant rate over the session, the rate drawn anew
for each session (``R`` per axis, data unit / s): the random-effect form of the
``bias_drift`` effect, the noise library's ``drift_ramp`` term.  Its kernel is the variogram
of its interval means, ``D_ij = R² (t̄_i − t̄_j)²`` (the pose midpoints' distance squared),
and within a rest it adds ``R² τ²/2`` to the Allan variance.  Registered with
``register_member``, it is in the grid of every wander family that does not list its
members (``one_process`` keeps the earlier three), the REML likelihood chooses it like any
other member, and
``tests/test_wander_member_conformance.py`` checks its kernel against its process's
stated covariance (``tests/test_examples.py`` runs those checks on it).  What the report
calls it is its process, a :class:`WanderProcess` that names the member
(``docs/extending.md``, "A wander process").  In the package the two classes are one entry
each of ``src/accelcal/discrepancy/wander/members.py`` and
``src/accelcal/discrepancy/wander_process.py``.

Run: ``python examples/custom_grid_member.py``.
"""

from __future__ import annotations

import math

import numpy as np

from accelcal.discrepancy.wander import GridMember, fit_common, problem, register_member, tau_grid
from accelcal.discrepancy.wander_process import FAMILIES, WanderProcess, process_of, register_process
from accelcal.noise.terms import TERMS, IntervalPairs, model_avar, noise_term


@register_member
class DriftRate(GridMember):
    id, code, has_tau, size_kind = "drift_rate", -2.0, False, "rate"
    region_note = "the 95 % region holds the drift-rate member (a bias changing at a constant random rate)"

    def variogram(self, taus, starts, durations, gap):
        return noise_term("drift_ramp").interval_difference_variance(1.0, None, IntervalPairs(starts, durations))

    def rest_avar(self, tau, taus, fs):
        return model_avar({"drift_ramp": 1.0}, taus, fs)


@register_process
class DriftRateProcess(WanderProcess):
    id, label, noise_term, member = "drift_rate", "bias drifting at a constant rate", "drift_ramp", "drift_rate"
    meaning = "a bias drifting at a constant random rate over the session: size is the rate R (data unit / s)"
    parameters = {"size": "the drift rate R per axis (data unit / s)"}
    example = {"tau": DriftRate.code, "q_abs": 1e-10}

    def tau_s(self, w):
        return math.nan

    def white_like(self, w, shortest):
        return False

    def time_correlated(self, w, shortest):
        return bool(w.present)

    def components(self, nm):
        return ((self.noise_term, float(nm["size"])),)

    def rest_allan(self, nm):
        R, basis = nm.get("size"), TERMS[self.noise_term]
        if R is None or not np.isfinite(R):
            return super().rest_allan(nm)
        return R, nm.get("size_ci") or [math.nan, math.nan], lambda taus, k, fs: k ** 2 * basis.basis(taus, fs, None)

    def reading(self, nm, words):
        return (f"bias drifting at a constant rate: R {words.size(nm.get('size'))}/s per axis "
                f"[{', '.join(f'{v:.3g}' for v in nm.get('size_ci') or [math.nan] * 2)}]{words.axes}{words.white}")

    def cell(self, nm, g):
        return f"drift rate {g(nm.get('size'))}/s", f"rate [{', '.join(map(g, nm.get('size_ci') or [None] * 2))}]"


def session(rng, rate: float, n: int = 36, sigma: float = 1e-3):
    """Pose residuals of ``n`` 4 s rests over ten minutes: white noise ``sigma`` plus a bias
    drifting at ``rate`` per axis (each axis its own rate), seen through random gravity directions."""
    starts = np.arange(n) * 16.0
    durations = np.full(n, 4.0)
    grad = rng.standard_normal((n, 3))
    grad /= np.linalg.norm(grad, axis=1, keepdims=True)
    bias = np.outer(starts + durations / 2, rate * rng.standard_normal(3))       # (n, 3)
    r = np.sum(grad * bias, axis=1) + sigma * rng.standard_normal(n)
    return problem(r, -grad, np.full(n, sigma), grad, starts, durations), starts, durations


if __name__ == "__main__":
    rng = np.random.default_rng(5)
    for rate in (2e-5, 0.0):  # a session that drifts, and one that does not
        prob, starts, durations = session(rng, rate)
        _, _, w = fit_common(prob, prob.X0)
        proc = process_of(w, prob.span)
        print(f"rate {rate:g}: grid of {prob.taus.size} codes, drift_rate's among them: "
              f"{bool(np.any(prob.taus == DriftRate.code))}; REML named: {proc.id} ({proc.label})"
              + (f", size {w.size:.3g}" if w.present else ""))
    print(f"in one_process's grid: {DriftRate.code in tau_grid(durations, prob.span, members=FAMILIES['one_process'].members)}")
