"""The deterministic layer under the white null: the F-test naming loop.

Given :class:`~accelcal.discrepancy.poses.PoseData`, the loop fits the base model (bias,
scale, non-orthogonality: 9 parameters), treats it as the simulation of the experiment,
and tests every candidate effect of the library as a nested extension of it.  The noise
model is white per-pose noise times a common scale; it is the benchmark's negative
control (on sessions whose bias wanders it names ``bias_drift`` far more often than α).

1. **Identifiability** (:func:`~accelcal.discrepancy.identifiability.identifiability`), before
   any test: a candidate that is not identifiable is refused, never named.
2. **Nested test** of current vs current + effect: the F-test on the weighted
   residuals, ``F = ((χ²₀ - χ²₁)/k) / (χ²₁/(n - q - k))`` against ``F(k, n - q - k)`` (``k``
   the effect's parameters: 3, or 7 for ``second_order``).
   Not the likelihood-ratio χ² test with the per-pose noise as known variance: the
   residuals of real recordings exceed that noise (Xsens: ≈ 3×, results/measured), and
   a test that takes the noise model as exact would call every candidate significant.
   The F-test estimates the common scale of the residuals from the extended model's own
   residuals, so it is exact for Gaussian errors whose covariance is known up to a
   factor.  Holm's step-down procedure controls the family-wise error across the
   identifiable candidates of a round (``correction='bonferroni'`` is available;
   ``'none'`` exists only as the negative control of the benchmark).
3. **ΔBIC** = ``n ln(χ²₁/χ²₀) + k ln n`` (Gaussian likelihood with the scale profiled
   out, as the F-test) must be below ``-bic_threshold``.
4. **Leave-one-pose-out** prediction error (PRESS, in noise units, each reduced fit
   warm-started from the full one) must fall below ``(1 - lopo_min_improvement)`` × that
   of the current model.

The best candidate among those passing 2–4 (smallest p-value, then smallest ΔBIC) is
named, the model is refitted with it, and the loop repeats with the remaining
candidates until none passes or ``max_rounds`` effects are named.  Each round is a
family tested at level α; a round is only reached if the previous one named an effect,
so on effect-free data the probability of naming anything is that of round 1: ≤ α.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from .fit import Fit, PoseData, effect_slices, fit, lopo
from .identifiability import Identifiability, applicable, identifiability
from .results import Candidate, DiscrepancyResult
from .rules import Rules
from .statistics import gap, holm


def _f_sf(stat: float, dfn: int, dfd: int) -> float:
    """:func:`accelcal.distributions.f_sf` for ``stat >= 0`` without its argument handling
    (the loop calls it for every candidate)."""
    return float(dist.special.fdtrc(dfn, dfd, stat)) if dfd > 0 else float("nan")



def _test_candidate(data: PoseData, current: Fit, lopo_cur: np.ndarray, ident: Identifiability,
                    rnd: int, rules: Rules, report: bool = True):
    eid = ident.effect
    row = Candidate.from_identifiability(ident, rnd)
    if not ident.identifiable:
        return row, None, None
    try:
        aug = fit(data, (*current.effects, eid), p0=current.p)
    except AccelcalError as err:
        return replace(row, identifiable=False, reasons=(*ident.reasons, f"fit failed: {err}")), None, None
    n = data.z.shape[0]
    k = len(ident.mde)  # the effect's parameters
    dof1 = aug.dof
    chi0, chi1 = current.chi2, aug.chi2
    stat = ((chi0 - chi1) / k) / (chi1 / dof1) if chi1 > 0 else float("inf")
    stat = max(stat, 0.0)
    p = _f_sf(stat, k, dof1)
    dbic = float(n * np.log(chi1 / chi0) + k * np.log(n)) if chi0 > 0 and chi1 > 0 else float("nan")
    if not report and not p <= rules.alpha:  # Holm's adjusted p is at least p: it cannot pass
        return replace(row, statistic=float(stat), dof=(k, dof1), p_value=p, delta_bic=dbic,
                       passed_bic=bool(dbic < -rules.bic_threshold)), aug, None
    lo = lopo(aug, data)
    both = np.isfinite(lo) & np.isfinite(lopo_cur)
    press0, press1 = (float(np.sum(lopo_cur[both] ** 2)), float(np.sum(lo[both] ** 2))) if both.any() else (np.nan,) * 2
    sl = effect_slices(aug.effects)[eid]
    cand = replace(row, statistic=float(stat), dof=(k, dof1), p_value=p, delta_bic=dbic,
                   lopo_gap_current=gap(lopo_cur[both]) if both.any() else float("nan"),
                   lopo_gap=gap(lo[both]) if both.any() else float("nan"),
                   estimate=aug.p[sl].tolist(), se=aug.standard_errors(True)[sl].tolist(),
                   se_noise=aug.standard_errors(False)[sl].tolist(),
                   passed_bic=bool(dbic < -rules.bic_threshold),
                   passed_lopo=bool(np.isfinite(press1) and press1 < (1 - rules.lopo_min_improvement) * press0))
    return cand, aug, lo


def discrepancy_white(data: PoseData, rules: Rules, report: bool = True) -> DiscrepancyResult:
    """The loop of the module docstring on one pose set (``rules.null == 'white'``).

    ``report=False``: the decisions only; a candidate whose p-value is above ``α`` (so that
    it cannot pass) keeps its test and ΔBIC but not its leave-one-pose-out gap and
    estimate (a benchmark's detection)."""
    cands, skipped = applicable(data, rules.candidates)
    base = fit(data)
    lopo_base = lopo(base, data)
    current, lopo_cur = base, lopo_base
    named, rows = [], []
    for rnd in range(1, rules.max_rounds + 1):
        remaining = [e for e in cands if e not in named]
        if not remaining:
            break
        tested = []
        for eid in remaining:
            ident = identifiability(data, current, eid, rules, len(remaining))
            tested.append(_test_candidate(data, current, lopo_cur, ident, rnd, rules, report))
        padj = holm([c.p_value for c, _, _ in tested], rules.correction)
        round_rows = []
        for (c, aug, lo), pa in zip(tested, padj):
            ok = bool(np.isfinite(pa) and pa <= rules.alpha)
            round_rows.append((replace(c, p_adjusted=float(pa), passed_test=ok), aug, lo))
        passing = [t for t in round_rows if t[0].passed]
        if passing:
            best = min(passing, key=lambda t: (t[0].p_value, t[0].delta_bic))
            round_rows = [(replace(c, named=c is best[0]), a, lo) for c, a, lo in round_rows]
        rows += [c for c, _, _ in round_rows]
        if not passing:
            break
        _, current, lopo_cur = best
        named.append(best[0].effect)
    return DiscrepancyResult(tuple(named), tuple(rows), skipped, base, current, lopo_base, lopo_cur, data, rules)


__all__ = ["discrepancy_white"]
