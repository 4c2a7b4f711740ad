"""The nested test that the gyroscope's and the magnetometer's loops share.

A candidate effect is a set of whitened columns ``Xw`` added to a sensor's whitened base
model ``base_w``; its F statistic is judged against the same statistic on null draws ``E``
(a parametric bootstrap: the residuals' noise model is what whitening made white), and its
minimum detectable effect comes from the noncentrality at which the F test has power 0.8.
"""

from __future__ import annotations

import numpy as np

from .statistics import critical_noncentrality

#: A candidate whose whitened columns the base model absorbs beyond this share is not identifiable.
MAX_ABSORBED = 0.99
#: Fewest degrees of freedom left after a candidate.
MIN_DOF = 4


def orthonormal_basis(A: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the columns of ``A`` (rank-revealing SVD)."""
    if A.shape[1] == 0:
        return A
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    return U[:, s > s[0] * 1e-10] if s.size and s[0] > 0 else U[:, :0]


def project_out(Q: np.ndarray, A: np.ndarray) -> np.ndarray:
    """``A`` with its part in the span of the orthonormal ``Q`` removed."""
    return A - Q @ (Q.T @ A)


def nested_f_test(base_w: np.ndarray, Xw: np.ndarray, rw: np.ndarray, E: np.ndarray, alpha: float, *,
                  unit: str = "motions", rows_per_unit: int = 2, base: str = "C") -> dict:
    """F test of the whitened columns ``Xw`` on top of ``base_w``, bootstrap p-value (null draws ``E``).

    ``alpha``: the level the MDE is computed at (the caller passes α over the number of
    candidates, the Bonferroni level Holm's first rejection needs).  ``unit`` and
    ``rows_per_unit`` name what the residuals come in (a gyro motion gives two; a
    magnetometer sample one), so that a session too short says how many it would need
    (``<unit>_needed``); ``base`` names the base model in the reason a candidate is not identifiable."""
    n = len(rw)
    Qb = orthonormal_basis(base_w)
    Xp = project_out(Qb, Xw)
    absorbed = 1.0 - np.sum(Xp ** 2, axis=0) / np.maximum(np.sum(Xw ** 2, axis=0), 1e-300)
    Z = orthonormal_basis(Xp)
    k, dof = Z.shape[1], n - Qb.shape[1] - Z.shape[1]
    row = {"absorbed": absorbed.tolist(), "k": int(Xw.shape[1]), "dof": int(dof)}
    if dof < MIN_DOF:
        need = int(np.ceil((n - dof + MIN_DOF) / rows_per_unit))
        return {**row, "status": "not_identifiable", f"{unit}_needed": need,
                "why": f"too few {unit}: {n // rows_per_unit} here, at least {need} needed for {Xw.shape[1]} "
                       "parameter(s)"}
    if k < Xw.shape[1] or np.any(absorbed > MAX_ABSORBED):
        return {**row, "status": "not_identifiable",
                "why": f"the {unit} cannot tell it from {base} (its columns absorbed by the base model)"}
    r0 = project_out(Qb, rw)
    num = float(np.sum((Z.T @ r0) ** 2))
    den = float(r0 @ r0) - num
    F = (num / k) / (den / dof)
    E0 = project_out(Qb, E)
    nb = np.sum((Z.T @ E0) ** 2, axis=0)
    Fb = (nb / k) / ((np.sum(E0 ** 2, axis=0) - nb) / dof)
    p = (1.0 + np.sum(Fb >= F)) / (1.0 + E.shape[1])
    s = np.sqrt(den / dof)  # the noise scale under the extended model
    lam = critical_noncentrality(k, dof, alpha, 0.8)
    mde = s * np.sqrt(lam) / np.linalg.norm(Xp, axis=0)
    return {**row, "status": "tested", "F": F, "p_value": float(p), "mde": mde.tolist(), "noise_scale": float(s),
            "excess_after": float(np.sqrt(den / dof))}


class LoopOutcome:
    """``outcome`` of a sensor loop's result from its ``named`` effects and first round's rows."""

    named: tuple[str, ...]
    rounds: list

    @property
    def outcome(self) -> str:
        if self.named:
            return "effect"
        rows = self.rounds[0].values() if self.rounds else []
        return "not_identifiable" if any(r["status"] == "not_identifiable" for r in rows) else "none"
