"""Before any test: can a candidate effect be told from the current model on this pose set?

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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..effects import ADDITIVE, EFFECTS, HARMONIC, TEMPERATURE, effect
from ..errors import AccelcalError
from ..extended_model import harmonic_basis
from .wander.problem import MIN_WANDER_DOF
from .fit import Fit, PoseData, effect_columns, orthonormal_basis
from .rules import Rules
from .statistics import critical_noncentrality

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


def pose_mean_change(eid: str, data: PoseData, base: Fit) -> np.ndarray:
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
    # the wander null re-estimates the wander under the alternative too: it needs its dof
    min_dof = MIN_WANDER_DOF if rules.null == "wander" else 1
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
        mde_data = np.max(pose_mean_change(eid, data, base), axis=0) * mde
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


def applicable(data: PoseData, candidates) -> tuple[list[str], dict]:
    """Candidates whose covariate exists in the recording, and why the others are not applicable."""
    ok, skipped = [], {}
    for eid in candidates:
        if EFFECTS[eid].covariate == TEMPERATURE and data.temp is None:
            skipped[eid] = "the recording has no temperature column"
        else:
            ok.append(eid)
    return ok, skipped


__all__ = ["Identifiability", "applicable", "identifiability", "pose_mean_change"]
