"""Observability of the filter: errors along and across the rotation axis over runs, and the
observability Gramian of eq. (7)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.batista.filter import observability_gramian
from .filter import FilterMonteCarlo


def observability_table(mc: FilterMonteCarlo, axis_body, case: str) -> pd.DataFrame:
    """Errors of ``g`` and ``b`` along the body axis ``n`` and across it, over runs.

    Columns ``case, t, component`` (``g_axial``, ``b_axial``, ``g_perp``, ``b_perp``),
    ``mean_error`` (signed for axial, mean norm for perp), ``rms_error``,
    ``filter_sigma`` (``sqrt(nᵀ P n)`` for axial, ``sqrt(tr P - nᵀ P n)`` for perp).
    """
    nvec = np.asarray(axis_body, float)
    nvec = nvec / np.linalg.norm(nvec)
    runs = mc.runs
    times = np.sort(runs["t"].unique())
    rows = []
    for name, blk in (("g", slice(3, 6)), ("b", slice(6, 9))):
        cols = [f"e_{name}_{a}" for a in "xyz"]
        E = runs[cols].to_numpy().reshape(-1, len(times), 3)  # (runs, times, 3)
        ax = E @ nvec
        perp = np.linalg.norm(E - ax[..., None] * nvec, axis=-1)
        Pb = mc.P[:, blk, blk]
        s_ax = np.sqrt(np.einsum("i,kij,j->k", nvec, Pb, nvec))
        s_perp = np.sqrt(np.clip(np.einsum("kii->k", Pb) - s_ax**2, 0, None))
        for comp, val, sig in ((f"{name}_axial", ax, s_ax), (f"{name}_perp", perp, s_perp)):
            rows.append(pd.DataFrame({"case": case, "t": times, "component": comp, "mean_error": val.mean(0),
                                      "rms_error": np.sqrt((val**2).mean(0)), "filter_sigma": sig}))
    return pd.concat(rows, ignore_index=True)


def gramian_table(t, omega, axis_body, case: str) -> pd.DataFrame:
    """Smallest eigenvalues of the observability Gramian of eq. (7) and the null direction.

    Columns ``case, window_s, eig_min, eig_max, eig_ratio, null_alignment`` with
    ``null_alignment = |v_min · (0, n, n)/√2|`` (1 when the unobservable direction is
    "equal shifts of g and b along the rotation axis").
    """
    W = observability_gramian(t, omega)
    ev, V = np.linalg.eigh(W)
    nvec = np.asarray(axis_body, float)
    nvec = nvec / np.linalg.norm(nvec)
    null = np.concatenate([np.zeros(3), nvec, nvec]) / np.sqrt(2)
    return pd.DataFrame([{"case": case, "window_s": float(t[-1] - t[0]), "eig_min": ev[0], "eig_max": ev[-1],
                          "eig_ratio": ev[0] / ev[-1], "null_alignment": float(abs(V[:, 0] @ null))}])


__all__ = ["gramian_table", "observability_table"]
