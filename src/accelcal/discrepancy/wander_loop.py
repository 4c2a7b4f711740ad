"""The deterministic layer under the wander null: the naming loop with the bias wander in the noise.

Each round (module :mod:`accelcal.discrepancy.wander` for the statistics):

1. The current model (base + what has been named, without the poses named as outliers)
   is fitted by weighted least squares (:func:`accelcal.discrepancy.fit.fit`) and
   linearised; the bias wander ``(s, τ)`` and its correlation ``φ`` between the sensor
   axes (a common-mode share, :func:`~.wander.fit_common`) are estimated by REML jointly
   with it; the round's tests, MDEs and LOPO stand at ``φ̂``.
2. Every applicable candidate effect gets the identifiability checks of the white loop
   (covariate, degrees of freedom, absorbed fraction, the design's MDE below ``max_mde_g``
   × g under the rests' noise) and its minimum detectable effect (MDE) under the fitted
   noise, reported.  ``wander_inflation`` is how much larger the wander makes the MDE
   than white noise of the same mean variance would (largest over the directions of the
   effect's parameters): large for effects whose signature is slow in time
   (``bias_drift``; ``temperature`` when the temperature changes slowly), about 1 for
   those that vary from pose to pose with the orientation.
3. Tests: the bootstrap likelihood-ratio test of every identifiable candidate, calibrated
   on the same replicates of the fitted null, and the outlier family (the largest
   studentised residual among the poses, against its exact null under the round's
   wander, :mod:`.wander.outliers`: thousands of draws where the decision needs them,
   not the bootstrap's floor of 0.005); Holm's step-down over the round's family (the
   candidates and, if enabled, the outlier family: one family, level α).
   The bootstrap has ``n_boot`` replicates; a test stops
   at its ``h``-th exceedance (Besag & Clifford's sequential p-value ``h/ℓ``, ``h`` the
   smallest count with ``h/n_boot > α``: such a test cannot pass with all replicates
   either: stopping changes no decision at ``n_boot``, and a stopped test is not grown).  Tests that do not pass but
   could with more replicates (the lower end of the 99 % Clopper–Pearson interval of
   their p-value would pass Holm) grow to ``5 (n_boot + 1) − 1`` replicates: 199
   replicates put the smallest p-value at 0.005, which Holm over six tests makes 0.03, so
   a strong effect with one replicate above it (p = 0.01, adjusted 0.06) was missed.  Only
   the power changes: a test that passes at ``n_boot`` keeps its p-value, and the first
   ``n_boot`` replicates are the same either way.  An effect passes when its adjusted p-value is ≤ α,
   ``ΔBIC = −LR + k ln n < −bic_threshold`` (``k`` its parameters) and the wander leave-one-pose-out PRESS
   (GLS prediction of each pose from the others, both models under the alternative's
   REML wander) falls; the outlier family when its adjusted p-value is ≤ α.
4. Passing candidates the data cannot tell apart (neither adds to the other: the
   likelihood ratio of each given the other, χ²₃ approximation at level α) are not named
   but reported ``not_identifiable`` (``ambiguous_with``); one that adds nothing to
   another that adds to it waits for the next round (``dominated``).
5. Of the rest, the one with the strongest evidence, the smallest ΔBIC, is named (the
   bootstrap p-values saturate at ``1/(n_boot + 1)`` and cannot rank strong results; an
   outlier's ΔBIC is ``−LR + 2 ln n``: one shift, one of ``n`` poses).  An effect joins
   the model; an outlier pose leaves the pose set (its residual is then predicted, not
   fitted).  The loop repeats until nothing passes, or ``max_rounds`` effects and
   ``max_outliers`` outliers are named.

How α is shared across rounds.  Every round tests its family (the remaining candidates
and the outlier family) at level α with Holm; a round is reached only when the previous
one named something.  On a recording with nothing to name, whatever is named is named in
round 1 or after a round-1 mistake, so the family-wise rate over all rounds, effects and
outliers together, is round 1's: at most α (up to the Monte Carlo error of the tests and
the plug-in of the wander).  After a correct round, the next tests what remains, again
at α (a step-down: the named items are no longer hypotheses).

A candidate that was tested, did not pass, and whose ``wander_inflation`` exceeds
``max_wander_inflation`` cannot be ruled out: it is reported ``not_identifiable`` with
the reason (the wander can produce what the effect would), never as absent.
"""

from __future__ import annotations

import math

# replace, not Candidate(**asdict(c)): asdict deep-copies every field (4 % of a benchmark chunk)
from dataclasses import dataclass, field, replace

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from . import wander as C
from .fit import Fit, PoseData, effect_columns, effect_slices, evaluate, fit, lopo
from .wander_model import linearise_noise, noise_model_dict, repeated_placements, wander_summary
from .identifiability import applicable, identifiability
from .results import Candidate, DiscrepancyResult, OutlierPose, OutlierTest
from .rules import Rules
from .statistics import critical_noncentrality, gap, holm

OUTLIER = "outlier_pose"


def _mde(info: np.ndarray, lam: float) -> np.ndarray:
    d = np.diag(info)
    return np.where(d > 0, np.sqrt(lam / np.where(d > 0, d, 1.0)), np.inf)


def _inflation(info_c: np.ndarray, info_sw: np.ndarray) -> float:
    """Largest ratio of the MDE under the wander to that under white noise of the same mean
    variance, over the directions of the parameter space: sqrt of the largest generalised
    eigenvalue of ``(I_sw, I_c)``."""
    try:
        ev = np.linalg.eigvals(np.linalg.solve(info_c, info_sw)).real
    except np.linalg.LinAlgError:
        return float("inf")
    ev = ev[np.isfinite(ev)]
    return float(np.sqrt(max(ev.max(), 0.0))) if ev.size else float("inf")


def _wander_dict(w: C.WanderFit) -> dict:
    return {"q_rel": w.q_rel, "tau_s": w.tau, "size": w.size, "K": w.K, "axis_correlation": w.common}


def _gls_estimate(prob: C.Problem, X1: np.ndarray, w1: C.WanderFit, aug: Fit, sl: slice) -> tuple[list, list]:
    """GLS estimate and standard error of the candidate's block (the last three columns of
    ``X1``) at the alternative's REML wander: the weighted nonlinear estimate of ``aug``
    plus the GLS − least-squares difference of the model linearised at the current fit."""
    try:
        beta_g, cov = C.gls_step(prob, X1, w1.t, w1.q_rel, w1.white_scale)
        beta_w, _ = C.gls_step(prob, X1, w1.t, 0.0)
    except np.linalg.LinAlgError:
        return [float("nan")] * 3, [float("nan")] * 3
    k = sl.stop - sl.start
    est = aug.p[sl] + beta_g[-k:] - beta_w[-k:]
    return est.tolist(), np.sqrt(np.clip(np.diag(cov)[-k:], 0.0, None)).tolist()


def discrepancy_wander(data: PoseData, rules: Rules, report: bool = True) -> DiscrepancyResult:
    """The loop of the module docstring on one pose set (``rules.null == 'wander'``).

    ``report``: also the final noise model with its profile-likelihood intervals and the
    gaps and excess under it (the report's; False: the noise model of the last round on the
    tests' grid, without intervals, and no excess reading: what a benchmark of the
    decisions needs)."""
    cands, _ = applicable(data, rules.candidates)
    base = fit(data)
    lopo_base = lopo(base, data)
    rng_seq = np.random.SeedSequence([int(rules.seed), 13])
    st = _LoopState(data, base, report=report)
    rnd = 0
    while True:
        rnd += 1
        remaining = ([e for e in cands if e not in st.named and e not in st.ambiguous]
                     if st.n_effects < rules.max_rounds else [])
        test_outliers = rules.outlier_pose and len(st.outliers) < rules.max_outliers
        if not remaining and not test_outliers:
            break
        try:
            prob, bas0, null = linearise_noise(st.data, st.current, rules.wander_family)
        except C.WanderError as err:
            st.wander_error = str(err)
            for eid in remaining:
                ident = identifiability(st.data, st.current, eid, rules, len(remaining))
                st.rows.append(_untested(ident, rnd, (*ident.reasons, f"bias wander cannot be estimated: {err}")))
            break
        st.noise = _RoundNoise(st.data, st.current, prob, bas0, null)
        rng = np.random.default_rng(rng_seq.spawn(1)[0])
        tested, out_test, rt = _round(st, prob, (bas0, null), remaining, test_outliers, rules, rnd, rng)
        best = _choose(tested, out_test)
        st.rows += [replace(r.candidate, named=r is best) for r in tested]
        if out_test is not None:
            st.outlier_tests.append(replace(out_test, named=best is out_test))
        if best is None:
            break
        if best is out_test:
            if not _drop_outlier(st, rt.outlier_pose, out_test):
                break
        else:
            st.named.append(best.candidate.effect)
            st.n_effects += 1
            st.current = best.fit
    return _result(data, rules, base, lopo_base, st, report)


@dataclass
class _RoundNoise:
    """The noise model a round stood at: its pose set and fit, their linearised problem, the
    :class:`~.wander.Basis` of the fit's columns and the REML noise (:func:`linearise_noise`)."""

    data: PoseData
    fit: Fit
    problem: C.Problem
    basis: C.Basis
    wander: C.WanderFit


@dataclass
class _LoopState:
    """What the loop has named so far, and the pose set and model it stands at."""

    data: PoseData
    current: Fit
    named: list[str] = field(default_factory=list)
    outliers: list[OutlierPose] = field(default_factory=list)
    rows: list[Candidate] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    outlier_tests: list[OutlierTest] = field(default_factory=list)
    ambiguous: set[str] = field(default_factory=set)
    n_effects: int = 0
    wander_error: str = ""
    noise: _RoundNoise | None = None   # of the last round's current model
    report: bool = True                # False: the decisions only (:func:`_tested_candidate`)


@dataclass(frozen=True)
class _Prepared:
    """A candidate of a round before its test: its row (identifiability and, if identifiable,
    the MDE under the fitted noise), the MDE under the rests' white noise, how much the
    wander inflates the MDE, and its contrast columns (None if not identifiable)."""

    row: Candidate
    mde_white: list
    inflation: float = float("nan")
    columns: np.ndarray | None = None

    @property
    def identifiable(self) -> bool:
        return self.row.identifiable


@dataclass(frozen=True)
class _Tested:
    """A candidate's row after the round's tests, its augmented weighted fit (None if the fit
    failed or it was not tested) and its contrast columns."""

    candidate: Candidate
    fit: Fit | None
    columns: np.ndarray | None

    @property
    def p_value(self) -> float:
        return self.candidate.p_value

    @property
    def delta_bic(self) -> float:
        return self.candidate.delta_bic


def _round(st: _LoopState, prob: C.Problem, noise: tuple, remaining, test_outliers: bool, rules: Rules, rnd: int,
           rng) -> tuple[list[_Tested], OutlierTest | None, C.RoundTests]:
    """One round: identifiability, the bootstrap tests, Holm, ΔBIC, LOPO, ambiguity.

    ``noise``: the :class:`~.wander.Basis` of the current model and its REML noise on
    ``prob`` (:func:`linearise_noise`).  Returns the candidates' rows, the outlier
    family's test (or None) and the round's :class:`~.wander.RoundTests`.
    """
    bas0, null = noise
    prepared = [_prepare(st.data, st.current, prob, null, eid, rules, len(remaining), rnd) for eid in remaining]
    testable = [r for r in prepared if r.identifiable]
    rt = C.round_tests(prob, [r.columns for r in testable], rng, rules.n_boot, outliers=test_outliers,
                       extend=_more_replicates_could_pass(rules), n_boot_max=5 * (rules.n_boot + 1) - 1,
                       alpha=rules.alpha, null=null, bas0=bas0)
    padj = holm([float(v) for v in rt.p_values] + ([rt.outlier_p] if test_outliers else []), rules.correction)
    lo0 = C.studentised(prob, prob.X0, null.t, null.q_rel)[1][0]
    tested = [_tested_candidate(st, prob, r, rt, k, padj[k], lo0, rules) for k, r in enumerate(testable)]
    tested = _resolve_ambiguous(prob, tested, rules.alpha)
    st.ambiguous |= {r.candidate.effect for r in tested if r.candidate.ambiguous_with}
    tested += [_Tested(_untested_from(r), None, None) for r in prepared if not r.identifiable]
    out_test = None
    if test_outliers:
        i, n = rt.outlier_pose, len(st.data)
        out_test = OutlierTest(round=rnd, pose=int(st.data.pose_index[i]), t=float(st.data.t[i]),
                               statistic=rt.outlier_lr, studentised=float(rt.outlier_t[i]), p_value=rt.outlier_p,
                               p_adjusted=float(padj[-1]), delta_bic=-rt.outlier_lr + 2.0 * math.log(n),
                               passed_test=bool(padj[-1] <= rules.alpha), draws=rt.outlier_draws)
    return tested, out_test, rt


def _more_replicates_could_pass(rules: Rules):
    """``extend(counts, n, final)`` for :func:`~.wander.round_tests`: the running tests
    that do not pass Holm at their p-value ``(1 + counts)/(n + 1)`` but would at the lower
    end of the 99 % Clopper–Pearson interval of their exceedance probability (floored at the
    smallest p-value of the grown bootstrap).  The stopped tests keep their p-value
    ``final`` (they cannot pass); a test that passes is not re-drawn."""
    floor = 1.0 / (5 * (rules.n_boot + 1))

    def extend(counts: np.ndarray, n: int, final: np.ndarray) -> np.ndarray:
        running = np.isnan(final)
        low = np.where(counts > 0, dist.beta_ppf(0.005, np.maximum(counts, 1), n - counts + 1), 0.0)
        p_now = np.where(running, (1 + counts) / (n + 1), final)
        p_low = np.where(running, np.maximum(low, floor), final)
        passes_now = holm(p_now, rules.correction) <= rules.alpha
        could_pass = holm(p_low, rules.correction) <= rules.alpha
        return running & could_pass & ~passes_now

    return extend


def _tested_candidate(st: _LoopState, prob: C.Problem, r: _Prepared, rt: C.RoundTests, k_test: int, p_adj: float,
                      lo0: np.ndarray, rules: Rules) -> _Tested:
    """The :class:`Candidate` row of a tested effect, with its augmented weighted fit.

    Without ``st.report`` (the decisions only, :func:`discrepancy_wander`), a candidate whose
    adjusted p-value is above α cannot pass whatever its ΔBIC and LOPO, so its estimate,
    LOPO and the alternative's noise are not computed (NaN): every decision and p-value
    is the same, at a fifth of the cost of such a row."""
    n = len(st.data)
    lr = float(rt.lr[k_test])
    size = r.columns.shape[1]  # the effect's parameters
    dbic = -lr + size * math.log(n)
    can_pass = bool(np.isfinite(p_adj) and p_adj <= rules.alpha)
    c = replace(r.row, statistic=lr, dof=(size, n - st.current.q - size), p_value=float(rt.p_values[k_test]),
                bartlett=float(rt.bartlett[k_test]), p_adjusted=float(p_adj), delta_bic=dbic,
                passed_test=False, passed_bic=bool(dbic < -rules.bic_threshold), passed_lopo=False,
                test="likelihood ratio, parametric bootstrap under the fitted noise",
                mde_white=r.mde_white, wander_inflation=r.inflation)
    aug, err = None, ""
    if st.report or can_pass:
        c, aug, err = _fitted_alternative(st, prob, r, rt, k_test, lo0, c, can_pass, rules)
    confounded = not c.passed and r.inflation > rules.max_wander_inflation
    c = replace(c, reasons=(*c.reasons, *([err] if err else [])), confounded_with_wander=confounded)
    return _Tested(c, aug, r.columns)


def _fitted_alternative(st: _LoopState, prob: C.Problem, r: _Prepared, rt: C.RoundTests, k_test: int,
                        lo0: np.ndarray, c: Candidate, can_pass: bool, rules: Rules) -> tuple[Candidate, Fit | None, str]:
    """The row ``c`` completed with what the alternative's fit gives: its REML noise, the
    LOPO comparison, the weighted nonlinear fit, the GLS estimate; the fit (None if it
    failed) and the failure's message."""
    X1 = np.hstack([prob.X0, r.columns])
    w1 = C.fit_wander(prob, X1, fine=False, bas=rt.bases[k_test + 1])
    # leave-one-pose-out under one covariance for both models (the alternative's REML noise):
    # the comparison then measures what the effect adds out of sample, not a change of the
    # wander's kriging
    lo1 = C.studentised(prob, X1, w1.t, w1.q_rel)[1][0]
    lo0c = C.studentised(prob, prob.X0, w1.t, w1.q_rel)[1][0]
    nan = [float("nan")] * r.columns.shape[1]
    est, se, se_noise, aug, err = nan, nan, nan, None, ""
    try:
        aug = fit(st.data, (*st.current.effects, r.row.effect), p0=st.current.p)
    except AccelcalError as e:
        err = f"{r.row.effect}: fit failed: {e}"
        st.errors.append(err)
    if aug is not None:
        sl = effect_slices(aug.effects)[r.row.effect]
        est, se = _gls_estimate(prob, X1, w1, aug, sl)
        se_noise = aug.standard_errors(False)[sl].tolist()
    c = replace(c, lopo_gap_current=gap(lo0), lopo_gap=gap(lo1), estimate=est, se=se, se_noise=se_noise,
                passed_test=bool(can_pass and aug is not None),
                passed_lopo=bool(np.sum(lo1 ** 2) < (1 - rules.lopo_min_improvement) * np.sum(lo0c ** 2)),
                wander_alt=_wander_dict(w1))
    return c, aug, err


def _choose(tested: list[_Tested], out_test: OutlierTest | None) -> _Tested | OutlierTest | None:
    """The result to name: among what passed (and is neither ambiguous nor dominated), the
    strongest evidence, the smallest ΔBIC (the bootstrap p-values saturate at
    ``1/(n_boot + 1)`` and cannot rank strong results), then the smallest p-value; the
    candidates before the outlier family on a tie.  None if nothing passed."""
    passing: list[_Tested | OutlierTest] = [r for r in tested if r.candidate.passed and not r.candidate.ambiguous_with
                                            and not r.candidate.dominated]
    if out_test is not None and out_test.passed_test:
        passing.append(out_test)
    return min(passing, key=lambda x: (x.delta_bic, x.p_value)) if passing else None


def _drop_outlier(st: _LoopState, i: int, test: OutlierTest) -> bool:
    """Name pose ``i`` (of the current pose set) an outlier and refit without it."""
    keep = np.arange(len(st.data)) != i
    new_data = st.data.subset(keep)
    try:
        new = fit(new_data, st.current.effects, p0=st.current.p)
    except AccelcalError as e:
        st.errors.append(f"refit without pose {int(st.data.pose_index[i])} failed: {e}")
        return False
    r_pred = _predict(st.data.subset(np.array([i])), new)
    st.outliers.append(OutlierPose(pose=int(st.data.pose_index[i]), t=float(st.data.t[i]), shift=r_pred,
                                   shift_sigma=r_pred / float(st.data.sigma[i]), statistic=test.statistic,
                                   studentised=test.studentised, p=test.p_value, p_adjusted=test.p_adjusted,
                                   round=test.round, gap_before=gap(st.current.weighted), gap_after=gap(new.weighted)))
    st.named.append(OUTLIER)
    st.data, st.current = new_data, new
    return True


#: A candidate lies inside a larger one when the current model with the larger reproduces at
#: least this share of every direction of the smaller's columns.  Exact nestings (``quadratic``
#: in ``second_order``: the degree-3 harmonics hold its radial signature but for the part the
#: bias absorbs) hold for the columns at ``|x| = g``; at the current fit ``|x|`` differs from g
#: by the residuals, up to a percent with strong effects, which leaves up to ~1e-4 of a
#: direction out (2e-4 measured with a 1.5 % quadratic); unrelated effects leave O(1).
NESTED_SHARE = 0.99


def nested(X0: np.ndarray, Xi: np.ndarray, Xj: np.ndarray) -> bool:
    """Whether candidate ``Xi`` lies inside the larger ``Xj`` (:data:`NESTED_SHARE`); two of
    the same size that reproduce each other are ambiguous, not nested."""
    if Xi.shape[1] >= Xj.shape[1]:
        return False
    Q, _ = np.linalg.qr(np.hstack([X0, Xj]))
    Ui, _ = np.linalg.qr(Xi)
    left = np.linalg.svd(Ui - Q @ (Q.T @ Ui), compute_uv=False)
    return bool(left.max() ** 2 <= 1.0 - NESTED_SHARE)


def _resolve_ambiguous(prob: C.Problem, tested: list[_Tested], alpha: float) -> list[_Tested]:
    """Pairs of passing candidates the data cannot tell apart (e.g. ``temperature`` and
    ``bias_drift`` when the temperature follows time).

    For passing candidates ``b`` and ``c``: ``b | c`` is the likelihood ratio of
    current + c + b against current + c (wander re-estimated, χ²_k approximation at level
    α).  Neither significant given the other: the pair is ambiguous, neither is named,
    both are reported ``not_identifiable`` (``ambiguous_with``).  Only one significant given
    the other: the other is explained by it and cannot be named this round (it is tested
    again after the refit).  A pair of which one lies inside the other (:func:`nested`) is
    never ambiguous: :func:`_nested_loser` waits."""
    passing = [(i, r.candidate, r.columns) for i, r in enumerate(tested) if r.candidate.passed]
    if len(passing) < 2:
        return tested
    X0 = prob.X0

    def ml(X):
        try:
            return float(C.profile(prob, X, prob.y[None], C.Q_REL_GRID).ml_min()[0])
        except np.linalg.LinAlgError:  # the pair's columns are collinear: neither adds to the other
            return float("nan")

    single = {i: ml(np.hstack([X0, Xe])) for i, _, Xe in passing}
    amb = {i: [] for i, _, _ in passing}
    drop = set()
    for a in range(len(passing)):
        for b in range(a + 1, len(passing)):
            (i, ci, Xi), (j, cj, Xj) = passing[a], passing[b]
            nest = (i, j) if nested(X0, Xi, Xj) else ((j, i) if nested(X0, Xj, Xi) else None)
            if nest is not None:
                small, large = nest
                cols = {k: Xe for k, _, Xe in passing}
                # given the other passing candidates: what the larger adds may be theirs
                others = [Xe for k, Xe in cols.items() if k not in nest and not nested(X0, Xe, cols[large])]
                Xo = np.hstack([X0, *others])
                lr = ml(np.hstack([Xo, cols[small]])) - ml(np.hstack([Xo, cols[large]]))
                drop.add(_nested_loser(nest, lr, tested, alpha / max(len(tested), 1)))
                continue
            both = ml(np.hstack([X0, Xi, Xj]))
            if np.isnan(both):
                i_given_j = j_given_i = False
            else:
                i_given_j = dist.chi2_sf(max(single[j] - both, 0.0), Xi.shape[1]) <= alpha
                j_given_i = dist.chi2_sf(max(single[i] - both, 0.0), Xj.shape[1]) <= alpha
            if not i_given_j and not j_given_i:
                amb[i].append(cj.effect)
                amb[j].append(ci.effect)
            elif not i_given_j:
                drop.add(i)
            elif not j_given_i:
                drop.add(j)
    return _relabelled(tested, amb, drop)


def _relabelled(tested: list[_Tested], amb: dict, drop: set) -> list[_Tested]:
    """``tested`` with the ambiguous pairs (``amb``: index -> the effects it cannot be told
    apart from) reported ``not_identifiable`` and the explained ones (``drop``) ``dominated``."""
    out = []
    for k, r in enumerate(tested):
        c = r.candidate
        if k in amb and amb[k]:
            c = replace(c, reasons=(*c.reasons, "cannot be told apart from " + ", ".join(amb[k]) + " on these poses"),
                        ambiguous_with=tuple(amb[k]))
        elif k in drop:
            c = replace(c, reasons=(*c.reasons, "explained by another passing candidate this round (tested again "
                                                "after the refit)"), dominated=True)
        out.append(_Tested(c, r.fit, r.columns))
    return out


def _nested_loser(pair: tuple[int, int], lr: float, tested: list[_Tested], level: float) -> int:
    """Of a passing pair ``(small, large)`` whose ``small`` lies inside ``large``, the one that
    waits: the larger unless it adds to the smaller, ``lr`` the likelihood ratio ``large |
    small`` given the round's other passing candidates (the pair's model is the larger
    one: what the larger adds may be another candidate's signal) on ``k_large − k_small``
    degrees of freedom, shrunk by the larger's ``bartlett`` factor (the stretch of its
    likelihood ratio under the round's bootstrap: the noise is re-estimated), at ``level``:
    α over the round's candidates (one more hypothesis of the round's family, Bonferroni:
    naming the larger claims more than the smaller)."""
    small, large = pair
    c_large = tested[large].candidate
    extra = tested[large].columns.shape[1] - tested[small].columns.shape[1]
    stretch = c_large.bartlett if np.isfinite(c_large.bartlett) and c_large.bartlett > 1 else 1.0
    lr = max(lr, 0.0) / stretch if np.isfinite(lr) else 0.0
    return small if extra > 0 and dist.chi2_sf(lr, extra) <= level else large


def _predict(one: PoseData, f: Fit) -> float:
    """Residual of a left-out pose under the fit ``f`` (unit of g)."""
    r, _, _ = evaluate(f.p, one, f.effects, jacobian=False)
    return float("nan") if r is None else float(r[0])


def _prepare(data: PoseData, current: Fit, prob: C.Problem, null: C.WanderFit, eid: str, rules: Rules, n_tests: int,
             rnd: int) -> _Prepared:
    ident = identifiability(data, current, eid, rules, n_tests)
    row = Candidate.from_identifiability(ident, rnd)
    if not ident.identifiable:
        return _Prepared(row, ident.mde.tolist())
    Xe = prob.columns(effect_columns(current.p, data, current.effects, eid))
    info = C.effect_information(prob, prob.X0, Xe, null.t, null.q_rel)
    lam = critical_noncentrality(Xe.shape[1], ident.dof, rules.alpha / max(n_tests, 1), rules.power)
    mde = _mde(info.wander, lam) * math.sqrt(null.white_scale)
    with np.errstate(invalid="ignore"):
        ratio = np.where(np.asarray(ident.mde) > 0, mde / np.asarray(ident.mde), np.inf)
    mde_data = np.asarray(ident.mde_data) * ratio
    infl = _inflation(info.wander, info.scaled_white)
    # the gate stays the design's (the rests' noise, as in the white loop): the noise fitted
    # under the current model also carries the effects not yet named, which would make a
    # strong effect refuse itself
    return _Prepared(replace(row, mde=mde.tolist(), mde_data=mde_data.tolist()), ident.mde.tolist(), infl, Xe)


def _untested(ident, rnd, reasons) -> Candidate:
    return replace(Candidate.from_identifiability(ident, rnd), identifiable=False, reasons=tuple(reasons),
                   test="not tested")


def _untested_from(r: _Prepared) -> Candidate:
    return replace(r.row, test="not tested", mde_white=r.mde_white)


def _result(data: PoseData, rules: Rules, base: Fit, lopo_base: np.ndarray, st: _LoopState,
            report: bool = True) -> DiscrepancyResult:
    cur_data, current = st.data, st.current
    lopo_final = lopo(current, cur_data) if not st.outliers else _lopo_full(current, cur_data, data)
    wander, prob, summary_w = None, None, {}
    wander_error = st.wander_error
    _, skipped = applicable(data, rules.candidates)
    if not report:
        last = st.noise
        prob, wander = (last.problem, last.wander) if last is not None else (None, None)
        return DiscrepancyResult(tuple(st.named), tuple(st.rows), skipped, base, current, lopo_base, lopo_final, data,
                                 rules, noise_model=noise_model_dict(wander, prob, wander_error),
                                 outliers=tuple(st.outliers), outlier_tests=tuple(st.outlier_tests),
                                 errors=tuple(st.errors), final_data=cur_data)
    try:
        last = st.noise
        if last is not None and last.data is cur_data and last.fit is current:
            prob, coarse = last.problem, last.wander
        else:
            prob, _, coarse = linearise_noise(cur_data, current, rules.wander_family)
        wander = replace(C.fit_wander(prob, prob.X0, fine=True), common_ci=coarse.common_ci,
                         common_profile=coarse.common_profile)
    except C.WanderError as err:
        wander_error = wander_error or str(err)
    except (AccelcalError, np.linalg.LinAlgError, ValueError) as err:
        st.errors.append(f"noise model fit failed: {err}")
    if wander is not None:
        summary_w = wander_summary(data, base, prob, wander, cur_data, current)
    placement = repeated_placements(cur_data, current, wander, alpha=rules.alpha) if wander is not None else None
    return DiscrepancyResult(tuple(st.named), tuple(st.rows), skipped, base, current, lopo_base, lopo_final, data,
                             rules, noise_model=noise_model_dict(wander, prob, wander_error, placement),
                             outliers=tuple(st.outliers), outlier_tests=tuple(st.outlier_tests),
                             errors=tuple(st.errors), final_data=cur_data, wander_summary=summary_w)


def _lopo_full(current: Fit, cur_data: PoseData, data: PoseData) -> np.ndarray:
    """Leave-one-pose-out errors on the full pose set: the kept poses' LOPO errors, the
    outliers' prediction errors (they are not in the fit), NaN-free, in noise units."""
    out = np.full(len(data), np.nan)
    kept = np.isin(data.pose_index, cur_data.pose_index)
    out[kept] = lopo(current, cur_data)
    for i in np.flatnonzero(~kept):
        out[i] = _predict(data.subset(np.array([i])), current) / data.sigma[i]
    return out
