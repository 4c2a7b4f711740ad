"""What the deterministic layer's two naming loops share: rules, identifiability, candidates, result.

The loops (:mod:`.white_loop` under the white null, :mod:`.wander_loop` under the colored
null; :func:`accelcal.discrepancy.detect.discrepancy` chooses) test every candidate effect
of the library as a nested extension of the current model (the base model of bias, scale
and non-orthogonality, 9 parameters, plus the effects named so far).  Both use the
decision :class:`Rules`, the identifiability checks below, the :class:`Candidate` rows and
the :class:`DiscrepancyResult` with its JSON.

Identifiability (:func:`identifiability`), before any test.  With ``J₀`` the weighted
Jacobian of the current model and ``J₁`` that of the effect's three parameters at zero
effect:

   * *absorbed* = the largest squared canonical correlation between the column spaces
     of ``J₁`` and ``J₀``: the fraction of the residual signature of the effect's worst
     direction that the current model reproduces by changing its own parameters
     (1 = rank-deficient augmented Jacobian, e.g. the quadratic term on the six faces);
   * *MDE* (minimum detectable effect) per axis: the size at which the nested F-test at
     level ``α/m`` (``m`` candidates in the round: Holm's first step) has the configured
     power, from the augmented Fisher information profiled over the current model,
     ``I_φ = J₁ᵀ (I - P₀) J₁`` (noise model = the per-pose standard errors): the
     non-centrality ``λ = φᵀ I_φ φ`` must reach ``λ*`` with
     ``P(F(k, n - q - k; λ*) > F_crit) = power`` (``k`` the effect's parameters: 3, one per
     axis, or 7 for ``second_order``); parameter j alone: ``φ_j = sqrt(λ*/I_φ,jj)``.
     It is also given in the data unit: the largest change of a pose mean that effect
     causes at that size.

   A candidate is *not identifiable* (refused, never named) when its covariate is
   missing or does not vary (temperature range below the configured minimum), when
   fewer than one residual degree of freedom would remain, when ``absorbed`` exceeds
   ``max_absorbed``, or when its MDE in the data unit exceeds ``max_mde_g`` × g.

Gap (:func:`gap`): the RMS of the weighted pose residuals, ``sqrt(χ²/n)``, with the same
fixed weights before (base model) and after (base + named effects); noise alone predicts
``sqrt((n - q)/n)``.  In-sample it can only shrink when parameters are added, so the
leave-one-pose-out gap ``sqrt(PRESS/n)`` is reported next to it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from functools import lru_cache

import numpy as np

from .. import distributions as dist
from ..errors import AccelcalError
from ..effects import ADDITIVE, HARMONIC
from ..extended_model import harmonic_basis
from .effects import EFFECT_IDS, EFFECTS, TEMPERATURE, effect
from .colored.problem import MIN_WANDER_DOF
from .fit import Fit, PoseData, effect_columns, evaluate, orthonormal_basis, parameter_names
from .schema import white_excess_status
from .summary import result_lines

CORRECTIONS = ("holm", "bonferroni", "none")
#: The noise models of the null hypothesis: ``colored`` (white per-pose noise + a bias wander
#: estimated jointly, :mod:`.wander_loop`), ``white`` (white per-pose noise times a common scale:
#: the F-test loop of this module).
NULLS = ("colored", "white")


@dataclass(frozen=True)
class Rules:
    """Decision rules of the loop (config ``discrepancy.rules``; defaults = config/config.yaml).

    ``null`` selects the noise model of the tests (:data:`NULLS`); ``n_boot`` and ``seed``
    the parametric bootstrap of the colored null; ``outlier_pose`` / ``max_outliers`` the
    outlier family (colored null only); ``max_wander_inflation`` when a candidate that did
    not pass counts as not identifiable against the wander (:mod:`.wander_loop`).
    """

    null: str = "colored"
    alpha: float = 0.05
    correction: str = "holm"
    bic_threshold: float = 2.0
    lopo_min_improvement: float = 0.0
    max_rounds: int = 3
    power: float = 0.8
    max_absorbed: float = 0.9999
    max_mde_g: float = 0.01
    min_temp_range: float = 0.5
    candidates: tuple[str, ...] = EFFECT_IDS
    n_boot: int = 199
    seed: int = 20240709
    outlier_pose: bool = True
    max_outliers: int = 3
    max_wander_inflation: float = 3.0

    def __post_init__(self):
        if self.null not in NULLS:
            raise AccelcalError(f"null must be one of {', '.join(NULLS)}, got {self.null!r}")
        if int(self.n_boot) != self.n_boot or self.n_boot < 19:
            raise AccelcalError(f"n_boot must be an integer >= 19 (p-values down to 0.05), got {self.n_boot}")
        if self.max_outliers < 0 or not self.max_wander_inflation >= 1:
            raise AccelcalError("need max_outliers >= 0 and max_wander_inflation >= 1")
        family = len(self.candidates) + bool(self.outlier_pose)
        if self.null == "colored" and (self.n_boot + 1) * self.alpha < family * (1 - 1e-9):
            raise AccelcalError(f"n_boot = {self.n_boot} cannot reach Holm's first level alpha/{family} (the smallest "
                                f"bootstrap p-value is 1/(n_boot + 1)): use n_boot >= {int(np.ceil(family / self.alpha)) - 1}")
        if not 0 < self.alpha < 1 or not 0 < self.power < 1:
            raise AccelcalError(f"need 0 < alpha < 1 and 0 < power < 1, got {self.alpha}, {self.power}")
        if self.correction not in CORRECTIONS:
            raise AccelcalError(f"correction must be one of {', '.join(CORRECTIONS)}, got {self.correction!r}")
        if self.max_rounds < 1 or not 0 < self.max_absorbed <= 1:
            raise AccelcalError("need max_rounds >= 1 and 0 < max_absorbed <= 1")
        object.__setattr__(self, "candidates", tuple(self.candidates))
        for e in self.candidates:
            effect(e)
        if len(set(self.candidates)) != len(self.candidates) or not self.candidates:
            raise AccelcalError("candidates must be a non-empty list of distinct effect ids")

    @classmethod
    def from_config(cls, cfg: dict) -> Rules:
        # YAML reads an unquoted ``null:`` key as None: take it for the ``null`` field
        cfg = {("null" if k is None else k): v for k, v in cfg.items()}
        return cls(**{k: (tuple(v) if k == "candidates" else v) for k, v in cfg.items()})


# --------------------------------------------------------------------------- helpers


def gap(weighted_residuals) -> float:
    """The gap between model and data: ``sqrt(mean((r_i/σ_i)²))`` (1 = noise level)."""
    w = np.asarray(weighted_residuals, float)
    w = w[np.isfinite(w)]
    return float(np.sqrt(np.mean(w * w))) if w.size else float("nan")


@lru_cache(maxsize=4096)
def critical_noncentrality(k: int, dof: int, level: float, power: float) -> float:
    """``λ*`` with ``P(F(k, dof; λ*) > F_{1-level}(k, dof)) = power`` (inf if ``dof < 1``)."""
    if dof < 1:
        return float("inf")
    fcrit = dist.f_isf(level, k, dof)

    def f(lam):
        return dist.ncf_sf(fcrit, k, dof, lam) - power

    hi = 1.0
    while f(hi) < 0:
        hi *= 2
        if hi > 1e8:
            return float("inf")
    from scipy.optimize import brentq  # here: scipy.optimize costs 0.2-0.6 s to import

    return float(brentq(f, 0.0, hi, xtol=1e-10, rtol=1e-12))


def holm(p_values, correction: str = "holm") -> np.ndarray:
    """Adjusted p-values (Holm step-down, Bonferroni, or none); NaN entries stay NaN."""
    p = np.asarray(p_values, float)
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    m = ok.size
    if m == 0:
        return out
    if correction == "none":
        out[ok] = p[ok]
    elif correction == "bonferroni":
        out[ok] = np.minimum(1.0, m * p[ok])
    else:
        order = ok[np.argsort(p[ok], kind="stable")]
        running = 0.0
        for j, i in enumerate(order):
            running = max(running, min(1.0, (m - j) * p[i]))
            out[i] = running
    return out


# --------------------------------------------------------------------------- identifiability


@dataclass(frozen=True)
class Identifiability:
    """Can an effect be tested against the current model on this pose set?

    ``mde`` in the effect's parameter unit (per parameter), ``mde_data`` the largest change
    of a pose mean it causes at that size (data unit); ``info`` = ``I_φ`` (k, k), the
    profiled Fisher information in noise units; ``lambda_crit`` = ``λ*``.
    """

    effect: str
    identifiable: bool
    reasons: tuple[str, ...]
    absorbed: float
    absorbed_axis: np.ndarray
    mde: np.ndarray
    mde_data: np.ndarray
    info: np.ndarray
    lambda_crit: float
    dof: int

    def mde_along(self, direction) -> float:
        """Size ``a`` of the MDE along the unit direction ``d`` in parameter space: ``φ = a d``."""
        d = np.asarray(direction, float)
        d = d / np.linalg.norm(d)
        v = float(d @ self.info @ d)
        return float(np.sqrt(self.lambda_crit / v)) if v > 0 else float("inf")


def _perturbation(eid: str, data: PoseData, base: Fit) -> np.ndarray:
    """(n, k) change of pose mean i (its length in the data unit) per unit of each of the
    effect's ``k`` parameters."""
    e = EFFECTS[eid]
    n = len(data)
    if e.kind == ADDITIVE:
        return np.repeat(np.abs(data.covariate(e.covariate))[:, None], 3, axis=1)
    if e.kind == HARMONIC:  # z moves by M T_m(x, x)
        moves = np.einsum("mjkl,nk,nl->nmj", harmonic_basis(e.power), base.x, base.x) @ base.M.T
        return np.linalg.norm(moves, axis=2)
    col = np.linalg.norm(base.M, axis=0)  # |M[:, j]|: how much P_j moves z
    x = np.abs(base.x)
    per = x if e.power == 1 else x ** e.power
    if e.covariate is not None:
        per = per * np.abs(data.covariate(e.covariate))[:, None]
    return per * col[None, :] if n else per


def identifiability(data: PoseData, base: Fit, eid: str, rules: Rules, n_tests: int) -> Identifiability:
    """Identifiability and minimum detectable effect of ``eid`` against the fitted ``base``.

    Parameters
    ----------
    data : PoseData
    base : Fit
        The current model (base + effects named so far).
    eid : str
        Candidate effect id.
    rules : Rules
    n_tests : int
        Candidates in the round (the MDE is computed at level ``alpha / n_tests``).
    """
    e = effect(eid)
    reasons = []
    n, q, k = len(data), base.q, e.size
    dof = n - q - k
    # the colored null re-estimates the wander under the alternative too: it needs its dof
    min_dof = MIN_WANDER_DOF if rules.null == "colored" else 1
    if e.covariate == TEMPERATURE:
        if data.temp is None:
            raise AccelcalError(f"{eid}: the recording has no temperature column (not applicable)")
        rng = float(np.ptp(data.temp))
        if rng < rules.min_temp_range:
            reasons.append(f"temperature varies by {rng:.3g} degC over the poses (< {rules.min_temp_range:g})")
    if dof < min_dof:
        reasons.append(f"{n} poses leave {dof} residual degrees of freedom for {q} + {k} parameters (the test needs "
                       f"{min_dof}: at least {q + k + min_dof} poses)")
    J1 = effect_columns(base.p, data, base.effects, eid) / data.sigma[:, None]
    U0, _ = base.column_basis
    U1, rank1 = orthonormal_basis(J1)
    rho = np.linalg.svd(U0.T @ U1, compute_uv=False) if rank1 else np.zeros(0)
    absorbed = 1.0 if rank1 < k else float(min(1.0, rho.max() ** 2))
    proj = U0 @ (U0.T @ J1)
    norms = np.sum(J1 * J1, axis=0)
    absorbed_axis = np.where(norms > 0, np.sum(proj * proj, axis=0) / np.where(norms > 0, norms, 1), 1.0)
    Jp = J1 - proj
    info = Jp.T @ Jp
    lam = critical_noncentrality(k, dof, rules.alpha / max(n_tests, 1), rules.power)
    diag = np.diag(info)
    mde = np.where(diag > 0, np.sqrt(lam / np.where(diag > 0, diag, 1)), np.inf)
    with np.errstate(invalid="ignore"):
        mde_data = np.max(_perturbation(eid, data, base), axis=0) * mde
    mde_data = np.where(np.isnan(mde_data), np.inf, mde_data)
    g_data = float(np.median(np.linalg.norm(data.z - base.bias, axis=1)))
    if rank1 < k:
        reasons.append(f"the effect's residual signature has rank {rank1} < {k} on this pose set"
                       + (" (it needs poses with three non-zero components, e.g. corners)"
                          if e.kind == HARMONIC else ""))
    elif absorbed > rules.max_absorbed:
        reasons.append(f"the base model absorbs {absorbed:.6f} of its worst direction (> {rules.max_absorbed:g})")
    worst = float(np.max(mde_data))
    if not reasons and not worst <= rules.max_mde_g * g_data:
        reasons.append(f"minimum detectable effect changes the pose means by {worst:.3g} "
                       f"(> {rules.max_mde_g:g} g = {rules.max_mde_g * g_data:.3g} in the data unit)")
    return Identifiability(eid, not reasons, tuple(reasons), absorbed, absorbed_axis, mde, mde_data, info, lam, dof)


# --------------------------------------------------------------------------- candidates, outliers, the result


@dataclass(frozen=True)
class Candidate:
    """One candidate in one round: identifiability, nested test, ΔBIC, LOPO, estimate."""

    round: int
    effect: str
    identifiable: bool
    reasons: tuple[str, ...]
    absorbed: float
    absorbed_axis: list
    mde: list
    mde_data: list
    statistic: float = float("nan")
    dof: tuple = (3, 0)
    p_value: float = float("nan")
    p_adjusted: float = float("nan")
    delta_bic: float = float("nan")
    lopo_gap_current: float = float("nan")
    lopo_gap: float = float("nan")
    estimate: list = field(default_factory=lambda: [float("nan")] * 3)
    se: list = field(default_factory=lambda: [float("nan")] * 3)
    se_noise: list = field(default_factory=lambda: [float("nan")] * 3)
    passed_test: bool = False
    passed_bic: bool = False
    passed_lopo: bool = False
    named: bool = False
    test: str = "F-test, common scale (white null)"
    mde_white: list = field(default_factory=lambda: [float("nan")] * 3)
    wander_inflation: float = float("nan")
    confounded_with_wander: bool = False
    wander_alt: dict = field(default_factory=dict)
    ambiguous_with: tuple = ()
    dominated: bool = False
    bartlett: float = float("nan")

    @classmethod
    def from_identifiability(cls, ident: Identifiability, rnd: int) -> Candidate:
        """The row of a candidate in round ``rnd`` before its test: its identifiability only."""
        nan = [float("nan")] * len(ident.mde)
        return cls(round=rnd, effect=ident.effect, identifiable=ident.identifiable, reasons=ident.reasons,
                   absorbed=ident.absorbed, absorbed_axis=ident.absorbed_axis.tolist(), mde=ident.mde.tolist(),
                   mde_data=ident.mde_data.tolist(), dof=(len(ident.mde), ident.dof), estimate=nan, se=nan,
                   se_noise=nan, mde_white=nan)

    @property
    def passed(self) -> bool:
        return self.identifiable and self.passed_test and self.passed_bic and self.passed_lopo

    def to_dict(self) -> dict:
        d = asdict(self)
        d["reasons"] = list(self.reasons)
        d["dof"] = list(self.dof)
        d["ambiguous_with"] = list(self.ambiguous_with)
        d["passed"] = self.passed
        d["parameters"] = list(EFFECTS[self.effect].parameters)
        d["unit"] = EFFECTS[self.effect].unit
        return d


@dataclass(frozen=True)
class OutlierTest:
    """The outlier family of one round (colored null): its most outlying pose and the test.

    ``pose`` is the pose's index in the recording, ``t`` its mid time [s]: the pose of the
    largest studentised residual, ``studentised`` (GLS, at the round's wander); ``p_value``
    the family's p-value against the exact null of that maximum (``draws`` Monte Carlo
    draws, :mod:`accelcal.discrepancy.colored.outliers`), ``p_adjusted`` after Holm over
    the round; ``statistic`` the pose's mean-shift likelihood ratio (the wander
    re-estimated), ``delta_bic`` = ``−LR + 2 ln n``.
    """

    round: int
    pose: int
    t: float
    statistic: float
    studentised: float
    p_value: float
    p_adjusted: float
    delta_bic: float
    passed_test: bool
    named: bool = False
    draws: int = 0

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class OutlierPose:
    """A pose named an outlier: left out of the fit, its residual predicted by the others.

    ``shift``: its residual under the refit without it (unit of g), ``shift_sigma`` the
    same over the pose's noise; the test's ``statistic``, ``studentised``, ``p`` and
    ``p_adjusted`` (:class:`OutlierTest`); the gaps of the model before and after.
    """

    pose: int
    t: float
    shift: float
    shift_sigma: float
    statistic: float
    studentised: float
    p: float
    p_adjusted: float
    round: int
    gap_before: float
    gap_after: float

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class DiscrepancyResult:
    """Outcome of the deterministic layer on one pose set.

    ``effect`` is the effect named in round 1 (or ``'none'``); ``outcome`` is the same,
    except ``'not_identifiable'`` when nothing was named and at least one applicable
    candidate was refused in round 1 (the recording cannot rule that effect out).
    """

    effects: tuple[str, ...]
    candidates: tuple[Candidate, ...]
    not_applicable: dict
    base: Fit
    final: Fit
    lopo_base: np.ndarray
    lopo_final: np.ndarray
    data: PoseData
    rules: Rules
    noise_model: dict = field(default_factory=dict)
    outliers: tuple[OutlierPose, ...] = ()
    outlier_tests: tuple[OutlierTest, ...] = ()
    errors: tuple = ()
    final_data: PoseData | None = None
    colored: dict = field(default_factory=dict)

    @property
    def effect(self) -> str:
        return self.effects[0] if self.effects else "none"

    @property
    def not_identifiable(self) -> tuple[str, ...]:
        """Candidates refused in round 1 and, under the colored null, those the last round
        could not rule out against the wander (never one that was named)."""
        return tuple(self.not_identifiable_reasons)

    @property
    def not_identifiable_reasons(self) -> dict:
        out = {c.effect: list(c.reasons) for c in self.candidates if c.round == 1 and not c.identifiable}
        if self.candidates and self.rules.null == "colored":
            for c in self.candidates:
                if c.ambiguous_with and c.effect not in self.effects:
                    out.setdefault(c.effect, list(c.reasons))
            last = max(c.round for c in self.candidates)
            for c in self.candidates:
                if c.round == last and c.effect not in self.effects and c.effect not in out:
                    if not c.identifiable:
                        out[c.effect] = list(c.reasons)
                    elif c.confounded_with_wander:
                        w = self.noise_model
                        out[c.effect] = [f"cannot be told apart from the bias wander (tau {w.get('tau_s', float('nan')):.3g} s): "
                                         f"it makes the minimum detectable effect {c.wander_inflation:.3g} x larger than "
                                         "white noise of the same size would, and the test did not pass"]
        return out

    @property
    def outcome(self) -> str:
        if self.effects:
            return self.effects[0]
        if self.errors:
            return "error"
        return "not_identifiable" if self.not_identifiable else "none"

    @property
    def gap_before(self) -> float:
        return gap(self.base.weighted)

    @property
    def gap_after(self) -> float:
        return gap(self.final.weighted)

    def residual_after_all(self) -> np.ndarray:
        """Residuals of the final model on every pose (outlier poses predicted, not fitted)."""
        if self.final_data is None or len(self.final_data) == len(self.data):
            return self.final.residuals
        r, _, _ = evaluate(self.final.p, self.data, self.final.effects, jacobian=False)
        return np.full(len(self.data), np.nan) if r is None else r

    def summary(self, unit: str | None = None) -> str:
        """The deterministic layer in a few lines (:func:`~accelcal.discrepancy.summary.result_lines`; ``unit``: the data's)."""
        return "\n".join(result_lines(self, unit))

    def statistics(self) -> dict:
        """The gaps and what noise alone predicts, before (base) and after (named effects)."""
        b, f = self.base, self.final
        chi0 = dist.chi2_sf(b.chi2, b.dof)  # NaN without degrees of freedom
        chi1 = dist.chi2_sf(f.chi2, f.dof)
        excess_var = b.chi2 - b.dof
        return {
            "n_poses": b.n,
            "gap_before": self.gap_before,
            "gap_after": self.gap_after,
            "gap_expected_before": float(np.sqrt(max(b.dof, 0) / b.n)),
            "gap_expected_after": float(np.sqrt(max(f.dof, 0) / f.n)),
            "gap_lopo_before": gap(self.lopo_base),
            "gap_lopo_after": gap(self.lopo_final),
            "excess_before": float(np.sqrt(b.chi2 / b.dof)) if b.dof > 0 else float("nan"),
            "excess_after": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
            "chi2_before": b.chi2, "dof_before": b.dof, "chi2_p_before": float(chi0),
            "chi2_after": f.chi2, "dof_after": f.dof, "chi2_p_after": float(chi1),
            # share of the χ² in excess of its expectation that the named effects remove
            "excess_explained_fraction": float((b.chi2 - f.chi2) / excess_var) if excess_var > 0 else float("nan"),
            **self.excess_readings(chi0, chi1),
        }

    def excess_readings(self, p_before: float, p_after: float) -> dict:
        """``excess_status`` under the model the loop used, and ``excess_status_white``.

        Both start from the base model's residuals against the rests' white noise alone
        (``no excess`` at level α: nothing to explain).  ``excess_status_white`` then asks
        the same of the final residuals: the named effects alone must bring them to the
        rests' noise.  ``excess_status`` asks it of the model the loop used: under the
        colored null the named effects (and outlier poses) *with* the named noise terms
        (white scale, bias wander or per-placement offset: ``excess_explained``, the final
        χ² inside the central 95 % of its predicted distribution); under the white null the
        two are the same.  Values: :data:`accelcal.discrepancy.schema.STATUS`.
        """
        white = white_excess_status(p_before, p_after, self.rules.alpha)
        out = {"excess_status_white": white, "excess_status": white,
               "excess_status_model": "white per-pose noise of the rests"}
        if self.rules.null != "colored":
            return out
        nm = self.noise_model or {}
        if white in ("no excess", "untestable"):
            return out  # nothing to explain, or nothing to test it with: the same under any noise model
        if not nm.get("estimated") or not self.colored or not self.colored.get("dof", 0) > 0:
            return {**out, "excess_status": "untestable",
                    "excess_status_model": "the colored null's noise model was not estimated"}
        term = nm.get("term", "none")
        model = "white per-pose noise of the rests x white scale" + ("" if term == "none" else f" + {term}")
        status = "explained" if self.colored.get("excess_explained") else "not explained"
        by = [e for e in self.effects if e != "outlier_pose"]
        if self.outliers:
            by.append(f"{len(self.outliers)} outlier pose(s) left out")
        if term != "none":
            by.append(term)
        ws_lo = (nm.get("white_scale_ci") or [float("nan")])[0]
        if ws_lo is not None and np.isfinite(ws_lo) and ws_lo > 1:
            by.append(f"white scale {nm.get('white_scale', float('nan')):.3g}")
        return {**out, "excess_status": status, "excess_status_model": model,
                "excess_explained_by": by if status == "explained" else []}

    def to_dict(self) -> dict:
        def params(f: Fit):
            names = parameter_names(f.effects)
            se = f.standard_errors(scaled=True)
            sen = f.standard_errors(scaled=False)
            return {nm: {"value": float(v), "se": float(s), "se_noise": float(sn)}
                    for nm, v, s, sn in zip(names, f.p, se, sen)}

        d = {
            "effect": self.effect,
            "effects": list(self.effects),
            "outcome": self.outcome,
            "null": self.rules.null,
            "not_identifiable": list(self.not_identifiable),
            "not_identifiable_reasons": self.not_identifiable_reasons,
            "errors": list(self.errors),
            "noise_model": self.noise_model or _white_noise_model(self),
            "outliers": [o.to_dict() for o in self.outliers],
            "outlier_tests": [o.to_dict() for o in self.outlier_tests],
            **self.colored,
            "not_applicable": dict(self.not_applicable),
            "candidates": [c.to_dict() for c in self.candidates],
            **self.statistics(),
            "rules": {**asdict(self.rules), "candidates": list(self.rules.candidates)},
            "model_before": {"effects": [], "parameters": params(self.base)},
            "model_after": {"effects": list(self.final.effects), "parameters": params(self.final)},
            "poses": {
                "t": self.data.t.tolist(),
                "temp": None if self.data.temp is None else self.data.temp.tolist(),
                "sigma": self.data.sigma.tolist(),
                "residual_before": self.base.residuals.tolist(),
                "residual_after": self.residual_after_all().tolist(),
                "excluded": [o.pose for o in self.outliers],
                "lopo_before": self.lopo_base.tolist(),
                "lopo_after": self.lopo_final.tolist(),
            },
        }
        return d


def _white_noise_model(res: DiscrepancyResult) -> dict:
    f = res.final
    return {"term": "none", "estimated": False, "process": "white per-pose noise times a common scale",
            "scale": float(np.sqrt(f.chi2 / f.dof)) if f.dof > 0 else float("nan"),
            "reason": "null 'white': the tests estimate a common scale of the per-pose noise; no bias wander"}



def applicable(data: PoseData, candidates) -> tuple[list[str], dict]:
    """Candidates whose covariate exists in the recording, and why the others are not applicable."""
    ok, skipped = [], {}
    for eid in candidates:
        if EFFECTS[eid].covariate == TEMPERATURE and data.temp is None:
            skipped[eid] = "the recording has no temperature column"
        else:
            ok.append(eid)
    return ok, skipped



__all__ = ["CORRECTIONS", "NULLS", "Candidate", "DiscrepancyResult", "Identifiability", "OutlierPose", "OutlierTest",
           "Rules", "applicable", "critical_noncentrality", "gap", "holm", "identifiability"]
