"""The round's tests: likelihood ratios calibrated by a parametric bootstrap under the fitted null,
and the outlier family calibrated by its exact null (:mod:`.outliers`).

Package docstring, "Tests (likelihood ratio, parametric bootstrap)" and "Outliers".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .gls import Q_REL_GRID, Basis, basis, grid_logdet, grid_ml_min, profile, studentised
from .outliers import directions, max_null_pvalue, studentised_max
from .problem import Problem
from .reml import WanderFit, fit_wander


@dataclass(frozen=True)
class RoundTests:
    """Bootstrap tests of one round: every candidate's LR and the outlier family."""

    lr: np.ndarray              # (k,) observed LR per candidate
    p_values: np.ndarray        # (k,) bootstrap p-values (1 + #{LR* ≥ LR})/(n_boot + 1)
    bartlett: np.ndarray        # (k,) mean(LR*)/3: how much estimating the noise stretches LR
    outlier_t: np.ndarray       # (n,) studentised residuals of the data (current model, null noise)
    outlier_p: float            # p-value of the largest |studentised residual| under its exact null
    outlier_pose: int           # index (into the current pose set) of that pose
    outlier_lr: float           # its mean-shift likelihood ratio (the wander re-estimated)
    null_wander: WanderFit      # the noise the bootstrap simulates (current model, REML)
    n_boot: int
    bases: tuple = ()           # Basis of the current model, then of each alternative
    outlier_draws: int = 0      # Monte Carlo draws of the outlier family's null


#: Bootstrap replicates are drawn in batches of these sizes (then repeating the last), so
#: that a test can stop early (:func:`round_tests`); the draws do not depend on them.
BATCHES = (25, 25, 50, 100)


def stop_count(alpha: float, n: int) -> int:
    """Exceedances after which a test stops (Besag & Clifford 1991): the smallest ``h`` with
    ``h/n > α``.  A test stopped at its ``h``-th exceedance after ``ℓ ≤ n`` replicates has the
    p-value ``h/ℓ > α``, and with all ``n`` it would have had ``(k + 1)/(n + 1) > α`` too
    (``k ≥ h``): stopping never changes whether it can pass at level ``α``."""
    return int(math.floor(alpha * n)) + 1


def round_tests(prob: Problem, X_alts: list, rng: np.random.Generator, n_boot: int,
                outliers: bool = True, extend=None, n_boot_max: int | None = None,
                alpha: float = 0.05, null: WanderFit | None = None, bas0: Basis | None = None,
                outlier_rng: np.random.Generator | None = None) -> RoundTests:
    """Likelihood-ratio tests current (``prob.X0``) vs current + each ``X_alts[k]``
    (contrast columns, appended to X0), calibrated on the same replicates simulated under
    the current model with its REML noise, and the outlier family: the largest
    studentised residual at that noise against its exact null (:mod:`.outliers`, drawn
    from ``outlier_rng``, default ``rng`` after the bootstrap), as many draws as its
    decision at level ``alpha`` over the round's Holm family needs (default stream: spawned
    from ``rng``, so the bootstrap's replicates do not depend on it).

    Sequential Monte Carlo p-values (Besag & Clifford 1991): a test stops at its
    :func:`stop_count`-th exceedance, with ``p = h/ℓ`` (``ℓ`` replicates used); one that
    runs to the end has ``p = (1 + k)/(n + 1)``.  Both are valid p-values, and a stopped
    test could not have passed at level ``alpha`` with every replicate either; what stopping
    saves is the replicates of tests that are clearly not significant.

    ``extend(counts, n, final)`` (optional): given the exceedance counts of the tests (the
    outlier family last, its p-value in ``final``: it is not bootstrapped) and the p-values
    of those that stopped (``final``, NaN while running) after ``n`` replicates, the mask
    of the tests for which more replicates could change a decision.  If any, those tests grow to
    ``n_boot_max`` replicates (their first
    ``n_boot`` are the same draws either way) and every other test keeps its p-value.
    ``null``, ``bas0``: the current model's REML noise (``fit_wander(prob, prob.X0,
    fine=False)``) and :class:`Basis`, if the caller has them."""
    X0 = prob.X0
    Xs = [np.hstack([X0, Xa]) for Xa in X_alts]
    bases = [basis(prob, X0) if bas0 is None else bas0] + [basis(prob, X1) for X1 in Xs]
    sf0 = profile(prob, X0, prob.y[None], Q_REL_GRID, shifts=outliers, bas=bases[0])
    logdet = grid_logdet(prob)   # every model's on this problem: computed once for the round
    m0 = float(grid_ml_min(bases[:1], prob.y, logdet, prob.m)[0, 0])
    # the bootstrap simulates the REML noise of the current model.  (Estimating it with the
    # most outlying pose free, against masking, was tried: under a random-walk wander it
    # lowered the simulated noise and raised the outlier family's false positives from
    # 7.5 % to 11 % and the candidates' from 5.3 % to 7.2 %, 120 sessions each.)
    null = fit_wander(prob, X0, fine=False) if null is None else null
    lr = np.array([max(m0 - float(grid_ml_min([b], prob.y, logdet, prob.m)[0, 0]), 0.0) for b in bases[1:]])
    o_i, o_lr, o_p, o_draws = -1, float("nan"), float("nan"), 0
    if outliers:  # first: the bootstrap's extension needs its p-value (its own stream: the replicates stay)
        tt, t_max = studentised_max(prob, bases[0], null.t, null.q_rel)
        o_i = int(np.argmax(np.abs(tt)))
        o_lr = float(max(m0 - float(sf0.shift_ml_min()[0, o_i]), 0.0))
        bhat, _ = directions(prob, bases[0], null.t, null.q_rel)
        o_p, o_draws = max_null_pvalue(bhat, t_max, rng.spawn(1)[0] if outlier_rng is None else outlier_rng,
                                       alpha=alpha, family=len(X_alts) + 1)
    seq = _Sequential(len(X_alts), stop_count(alpha, n_boot))
    if X_alts:
        _bootstrap(prob, bases, logdet, lr, rng, null, seq, n_boot, n_boot_max, alpha,
                   None if extend is None else _with_fixed(extend, outliers, o_p))
    t_obs, _ = studentised(prob, X0, null.t, null.q_rel, scale=null.white_scale)
    return RoundTests(lr=lr, p_values=seq.p_values(), bartlett=seq.mean_lr(X_alts),
                      outlier_t=t_obs[0], outlier_p=float(o_p), outlier_pose=o_i, outlier_lr=o_lr,
                      null_wander=null, n_boot=int(seq.n), bases=tuple(bases), outlier_draws=int(o_draws))


def _with_fixed(extend, outliers: bool, p_outlier: float):
    """``extend`` of :func:`round_tests` seeing the outlier family last, as a test that has
    stopped at its p-value ``p_outlier``."""
    if not outliers:
        return extend

    def wrapped(counts, n, final):
        return extend(np.append(counts, 0), n, np.append(final, p_outlier))[:-1]

    return wrapped


def _bootstrap(prob: Problem, bases: list, logdet: np.ndarray, observed: np.ndarray, rng, null: WanderFit, seq,
               n_boot: int, n_boot_max: int | None, alpha: float, extend) -> None:
    """The sequential bootstrap of the candidates' likelihood ratios (:func:`round_tests`;
    ``logdet``: the round's :func:`~.gls.grid_logdet`)."""
    # replicates drawn through the Cholesky factor of the null covariance: unique, unlike the
    # eigenvectors (whose signs depend on the LAPACK routine), so the replicates are too
    root = np.linalg.cholesky(null.white_scale * prob.sigma_c(null.t, null.q_rel))
    cap, k = n_boot, 0
    while True:
        batch = min(BATCHES[min(k, len(BATCHES) - 1)], cap - seq.n)
        Ystar = rng.standard_normal((batch, prob.m)) @ root.T
        seq.add(_bootstrap_batch(prob, bases, logdet, Ystar, seq.running), observed)
        k += 1
        if not seq.running.any():
            break
        if seq.n == cap:
            grow = (extend(seq.counts, seq.n, seq.final) if cap == n_boot and extend is not None
                    and n_boot_max is not None and n_boot_max > n_boot else None)
            if grow is None or not np.any(grow):
                break
            seq.freeze(~np.asarray(grow, bool))   # the others keep their p-value at n_boot
            cap = n_boot_max
            seq.h = stop_count(alpha, n_boot_max)   # the running tests have fewer exceedances than that


class _Sequential:
    """Exceedance counts of tests that stop at their ``h``-th exceedance (:func:`round_tests`)."""

    def __init__(self, k: int, h: int):
        self.counts = np.zeros(k, dtype=np.int64)
        self.used = np.zeros(k, dtype=np.int64)     # replicates each test has used
        self.sums = np.zeros(k)                     # sum of its replicate statistics
        self.final = np.full(k, np.nan)             # p-value of a stopped test
        self.n, self.h = 0, h

    @property
    def running(self) -> np.ndarray:
        return np.isnan(self.final)

    def add(self, stats_: np.ndarray, observed: np.ndarray) -> None:
        """Replicate statistics ``stats_`` (b, k) (NaN for the stopped tests) against the
        observed ones: count, and stop the tests that reach ``h`` exceedances."""
        tol = 1e-9 * np.maximum(1.0, np.nan_to_num(observed, nan=0.0))
        for j in np.flatnonzero(self.running):
            x = stats_[:, j]
            cum = self.counts[j] + np.cumsum(x >= observed[j] - tol[j])
            hit = np.flatnonzero(cum >= self.h)
            last = int(hit[0]) + 1 if hit.size else x.size
            self.counts[j], self.used[j] = cum[last - 1], self.used[j] + last
            self.sums[j] += float(np.sum(x[:last]))
            if hit.size:
                self.final[j] = self.h / self.used[j]
        self.n += stats_.shape[0]

    def freeze(self, mask: np.ndarray) -> None:
        """Stop the running tests of ``mask`` at their current p-value."""
        keep = mask & self.running
        self.final[keep] = ((1 + self.counts) / (self.used + 1))[keep]

    def p_values(self) -> np.ndarray:
        return np.where(self.running, (1 + self.counts) / (self.used + 1), self.final)

    def mean_lr(self, X_alts) -> np.ndarray:
        if not X_alts:
            return np.zeros(0)
        k = len(X_alts)
        return self.sums[:k] / np.maximum(self.used[:k], 1) / np.array([Xa.shape[1] for Xa in X_alts])


def _bootstrap_batch(prob: Problem, bases: list, logdet: np.ndarray, Ystar: np.ndarray,
                     running: np.ndarray) -> np.ndarray:
    """Replicates ``Ystar`` (B, m) drawn under the null, refitted as the data: per replicate
    the LR of each candidate, NaN for the tests no longer ``running``.  The candidates with
    as many free contrasts are refitted together (:func:`~.gls.grid_ml_min`)."""
    out = np.full((Ystar.shape[0], len(running)), np.nan)
    m0s = grid_ml_min(bases[:1], Ystar, logdet, prob.m)[0]
    todo = np.flatnonzero(running[:len(bases) - 1])
    for r in sorted({bases[k + 1].K.shape[1] for k in todo}):
        group = [k for k in todo if bases[k + 1].K.shape[1] == r]
        m1s = grid_ml_min([bases[k + 1] for k in group], Ystar, logdet, prob.m)
        out[:, group] = np.maximum(m0s[:, None] - m1s.T, 0.0)
    return out



__all__ = ["BATCHES", "RoundTests", "round_tests", "stop_count"]
