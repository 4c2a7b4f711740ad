"""The oracle of the discrepancy benchmark: the loop's nested tests with the true noise covariance.

The simulator knows each recording's noise: the covariance of its pose residuals follows
from the profile (:func:`.profiles.pose_residual_covariance`, on the poses the static
detection found, through the base fit's gradients).  The oracle runs the loop's decisions
on the same pose means with that covariance instead of an estimate: generalised least
squares, nothing estimated, every test exact.  What the loop names and the oracle does
not (or the reverse) is what estimating the noise costs (:mod:`.scoring`).

One round (as in :mod:`accelcal.discrepancy.wander_loop`, the model linearised at the base
fit: an effect moves a pose residual by ~1e-4 of g, the neglected terms are ~1e-8):

* candidates: the loop's identifiability gate at the base fit (the same refusals), then
  the likelihood ratio of current vs current + effect, ``LR = χ²(X) − χ²([X, J_e])`` under
  the true covariance, exactly ``χ²_k`` without the effect;
* outlier family: the largest studentised residual ``max_i |(P r)_i|/sqrt(P_ii)`` against
  its exact null (:func:`accelcal.discrepancy.wander.max_null_pvalue`, known variance);
  a named outlier is a free shift of its pose (its indicator joins the columns);
* Holm over the round's family at level α; an effect passes with ``ΔBIC = −LR + k ln n <
  −bic_threshold`` and a leave-one-pose-out PRESS (GLS, true covariance) that falls;
  passing pairs that cannot be told apart are not named (exact χ² at α), a candidate
  inside a larger one is named unless the larger adds to it (at α over the round);
  the smallest ΔBIC is named (an outlier's: ``−t² + 2 ln n``); at most ``max_rounds``
  effects and ``max_outliers`` outliers.

Real-record profiles have no known truth: their "true" covariance is the record's fitted
model, so there the oracle is the loop given the right model family and its parameters.
No oracle in the strict sense exists for them: the record's noise is one realisation of
an unknown process, and any covariance handed to the oracle is itself an estimate (for
``adis_real``, the model fitted to 2.78 h of the same record: the loop's disagreement with
it mixes what estimating the noise costs with where that model is wrong).  The profile
whose oracle deserves the name is its simulated twin, ``adis_model``: recordings whose
true noise *is* the fitted model, so the oracle knows it exactly; ``adis_real`` then
measures what the real noise adds beyond the model (transients screened out), and its
agreement is a comparison with a reference, not with an oracle.
"""

from __future__ import annotations

import math

import numpy as np

from accelcal import distributions as dist
from accelcal.discrepancy.wander import max_null_pvalue
from accelcal.discrepancy.fit import Fit, PoseData, effect_columns, fit
from accelcal.discrepancy.identifiability import applicable, identifiability
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.statistics import holm
from accelcal.discrepancy.wander_loop import OUTLIER, nested
from accelcal.errors import AccelcalError

from .profiles import pose_residual_covariance

#: The named set's name of an outlier pose (with its index in the detected pose set).
OUTLIER_TAG = "outlier_pose@"


class _Gls:
    """Generalised least squares of the residuals ``r`` under the covariance ``S`` (whitened once)."""

    def __init__(self, r: np.ndarray, S: np.ndarray):
        self.W = np.linalg.inv(np.linalg.cholesky(S))
        self.r = r
        self.y = self.W @ r

    def chi2(self, X: np.ndarray) -> float:
        """``min_β |W (r − X β)|²``."""
        Q, _ = np.linalg.qr(self.W @ X)
        e = self.y - Q @ (Q.T @ self.y)
        return float(e @ e)

    def residual_map(self, X: np.ndarray) -> np.ndarray:
        """``A = (I − H) W`` (n, n): ``P = AᵀA`` is the GLS residual projector in the pose space."""
        Q, _ = np.linalg.qr(self.W @ X)
        return self.W - Q @ (Q.T @ self.W)

    def lopo_press(self, X: np.ndarray) -> float:
        """Σ_i ((P r)_i / P_ii)²: the GLS leave-one-pose-out errors (kriging included)."""
        A = self.residual_map(X)
        pr = A.T @ (A @ self.r)
        d = np.einsum("ij,ij->j", A, A)
        ok = d > 1e-12 * d.max()
        return float(np.sum((pr[ok] / d[ok]) ** 2))


def _outlier_test(gls: _Gls, X: np.ndarray, excluded: set, rng, alpha: float, family: int):
    """``(pose, t², p, draws)`` of the outlier family at the current columns ``X``."""
    A = gls.residual_map(X)
    norms = np.linalg.norm(A, axis=0)
    ok = norms > 1e-9 * norms.max()
    ok[list(excluded)] = False
    bhat = np.where(ok[:, None], A.T / np.where(ok, norms, 1.0)[:, None], 0.0)
    t = bhat @ (A @ gls.r)
    i = int(np.argmax(np.abs(t)))
    p, draws = max_null_pvalue(bhat, float(abs(t[i])), rng, alpha=alpha, family=family, studentised=False)
    return i, float(t[i] ** 2), p, draws


def _resolve(gls: _Gls, X: np.ndarray, passing: list, cols: dict, alpha: float, level: float):
    """The passing effects that may be named: ambiguous pairs out, the loser of a nested pair out."""
    out = set(passing)
    chi0 = {e: gls.chi2(np.hstack([X, cols[e]])) for e in passing}
    for a in range(len(passing)):
        for b in range(a + 1, len(passing)):
            i, j = passing[a], passing[b]
            Xw, Wi, Wj = gls.W @ X, gls.W @ cols[i], gls.W @ cols[j]
            pair = (i, j) if nested(Xw, Wi, Wj) else ((j, i) if nested(Xw, Wj, Wi) else None)
            if pair is not None:
                small, large = pair
                extra = cols[large].shape[1] - cols[small].shape[1]
                # given the other passing candidates (the loop's rule): what the larger adds may be theirs
                others = [cols[k] for k in passing if k not in pair
                          and not nested(Xw, gls.W @ cols[k], gls.W @ cols[large])]
                Xo = np.hstack([X, *others])
                lr = gls.chi2(np.hstack([Xo, cols[small]])) - gls.chi2(np.hstack([Xo, cols[large]]))
                adds = dist.chi2_sf(max(lr, 0.0), extra) <= level
                out.discard(small if adds else large)
                continue
            both = gls.chi2(np.hstack([X, cols[i], cols[j]]))
            i_given_j = dist.chi2_sf(max(chi0[j] - both, 0.0), cols[i].shape[1]) <= alpha
            j_given_i = dist.chi2_sf(max(chi0[i] - both, 0.0), cols[j].shape[1]) <= alpha
            if not i_given_j and not j_given_i:
                out -= {i, j}
            elif not i_given_j:
                out.discard(i)
            elif not j_given_i:
                out.discard(j)
    return out


def oracle_loop(data: PoseData, cov_r: np.ndarray, rules: Rules, rng: np.random.Generator,
                gate: dict | None = None, base: Fit | None = None) -> dict:
    """The oracle's decisions on one pose set (module docstring).

    Parameters
    ----------
    data : PoseData
        The detected poses (the loop's).
    cov_r : ndarray (n, n)
        True covariance of their residuals (unit of g²).
    rules : Rules
    rng : Generator
        Draws of the outlier family's null.
    gate : dict, optional
        ``{effect: identifiable}`` at the base fit, if the loop has it (its round 1: the
        same check on the same poses); computed otherwise.
    base : Fit, optional
        The base model fitted to ``data`` (``fit(data)``), if the caller has it.

    Returns
    -------
    dict
        ``effects`` (named, in order, '+'-joined, ``outlier_pose`` for an outlier as the
        loop writes it), ``outlier_poses_detected`` (';'-joined pose indices) and
        ``outlier_t_detected`` (their mid times, as the loop's rows),
        ``named_set`` (effects and ``outlier_pose@i``, sorted, '+'-joined), ``outcome``.
    """
    base = fit(data) if base is None else base
    n = len(data)
    gls = _Gls(base.residuals, cov_r)
    cands, _ = applicable(data, rules.candidates)
    if gate is None or set(gate) != set(cands):
        gate = {e: identifiability(data, base, e, rules, len(cands)).identifiable for e in cands}
    cols = {e: effect_columns(base.p, data, (), e) for e in cands if gate[e]}
    X = base.J * base.sigma[:, None]
    named, outliers = [], []
    while True:
        remaining = [e for e in cols if e not in named] if len(named) < rules.max_rounds else []
        test_out = rules.outlier_pose and len(outliers) < rules.max_outliers
        if not remaining and not test_out:
            break
        choices, pose = _round_choices(gls, X, cols, remaining, test_out, outliers, rng, rules)
        if not choices:
            break
        best = min(choices, key=lambda k: (choices[k], k == OUTLIER, k))
        if best == OUTLIER:
            outliers.append(pose)
            named.append(OUTLIER)
            X = np.hstack([X, np.eye(n)[:, [pose]]])
        else:
            named.append(best)
            X = np.hstack([X, cols[best]])
    idx = [int(data.pose_index[i]) for i in outliers]
    effects = [e for e in named if e != OUTLIER]
    return {"effects": "+".join(named), "outcome": named[0] if named else _nothing(gate),
            "outlier_poses_detected": ";".join(map(str, idx)),
            "outlier_t_detected": ";".join(f"{data.t[i]:.3f}" for i in outliers),
            "named_set": named_set(effects, idx)}


def _round_choices(gls: _Gls, X: np.ndarray, cols: dict, remaining: list, test_out: bool, outliers: list,
                   rng: np.random.Generator, rules: Rules) -> tuple[dict, int | None]:
    """One round of :func:`oracle_loop`: the candidates (and the outlier family) that pass the
    test under the true covariance (Holm), ΔBIC and PRESS, and are not ambiguous, with their
    ΔBIC (the smallest is named); the round's most outlying pose (None: not tested)."""
    n = X.shape[0]
    pose = None
    chi_x = gls.chi2(X)
    lr = {e: max(chi_x - gls.chi2(np.hstack([X, cols[e]])), 0.0) for e in remaining}
    p = [dist.chi2_sf(lr[e], cols[e].shape[1]) for e in remaining]
    family = len(remaining) + bool(test_out)
    if test_out:
        pose, t2, p_out, _ = _outlier_test(gls, X, set(outliers), rng, rules.alpha, family)
        p.append(p_out)
    padj = holm(p, rules.correction)
    passing = [e for e, pa in zip(remaining, padj) if pa <= rules.alpha
               and -lr[e] + cols[e].shape[1] * math.log(n) < -rules.bic_threshold]
    if passing:  # the PRESS of those that pass the test and ΔBIC (the others cannot pass)
        press0 = gls.lopo_press(X)
        passing = [e for e in passing if gls.lopo_press(np.hstack([X, cols[e]]))
                   < (1 - rules.lopo_min_improvement) * press0]
    choices = {e: -lr[e] + cols[e].shape[1] * math.log(n)
               for e in _resolve(gls, X, passing, cols, rules.alpha, rules.alpha / max(len(remaining), 1))}
    if test_out and padj[-1] <= rules.alpha:
        choices[OUTLIER] = -t2 + 2.0 * math.log(n)
    return choices, pose


def _nothing(gate: dict) -> str:
    return "not_identifiable" if not all(gate.values()) else "none"


def _gate(rows: list, candidates) -> dict | None:
    """``{effect: identifiable}`` of a loop's detection row (round 1), None if no row has it."""
    for row in rows:
        g = {e: bool(row[f"identifiable_{e}"]) for e in candidates if f"identifiable_{e}" in row}
        if g:
            return g
    return None


def named_set(effects, outlier_poses) -> str:
    """The set a detector names, as one string: its effects and its outlier poses (by index)."""
    items = {e for e in effects if e and e != OUTLIER} | {f"{OUTLIER_TAG}{int(i)}" for i in outlier_poses}
    return "+".join(sorted(items))


def oracle_detection(data: PoseData, profile, fs: float, rules: Rules, rng: np.random.Generator,
                     loop_rows: list | None = None) -> dict:
    """The oracle's detection row on the detected poses ``data`` of a recording simulated with
    ``profile`` at ``fs`` [Hz] (null ``oracle``), as :func:`.benchmark.detect_nulls` writes
    the loop's; ``error`` if the covariance or the fit fails.  ``loop_rows``: the loop's rows
    on the same poses (their round-1 ``identifiable_*`` is the oracle's gate)."""
    row = {"null": "oracle", "outcome": "error", "effect": "", "effects": "", "error": ""}
    try:
        base = fit(data)
        durations = data.t_end - data.t_start + 1.0 / fs
        w = -(base.J[:, :3] * base.sigma[:, None])      # ∂r/∂z
        cov = pose_residual_covariance(profile, data.t_start, durations, np.round(durations * fs), fs, w)
        out = oracle_loop(data, cov, rules, rng, _gate(loop_rows or [], rules.candidates), base)
    except (AccelcalError, np.linalg.LinAlgError) as err:
        row["error"] = str(err).splitlines()[0]
        return row
    return {**row, **out, "effect": out["effects"].split("+")[0] if out["effects"] else "none"}


__all__ = ["OUTLIER_TAG", "named_set", "oracle_detection", "oracle_loop"]
