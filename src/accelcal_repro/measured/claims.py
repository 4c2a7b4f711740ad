"""Claims-ledger rows for the papers' real-data results (stage ``measured``).

Burkhard et al. (2024) Table 1 and Batista et al. (2011) Sec. VI-B report calibrations
of their own sensors (ADIS-16475 and STIM318; a Silicon Designs accelerometer on a
motion rate table) whose recordings are not public: those results are
``not_reproducible``.  The evidence of each row gives the reason, then what the closest
public analogue measured here shows (computed from the stage's tables, never typed
in), so that a reader sees what *can* be said about real data with these methods.

Claim ids differ from the foundation stage's ``table1_field_tests`` (one general row):
these rows split Table 1 into its laboratory (full LLS) and field (bias-only) parts.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from accelcal.registry import model_of

from ..claims import COLUMNS, Claim, validate_rows


def _row(df: pd.DataFrame, **where) -> pd.Series | None:
    sel = df
    for k, v in where.items():
        sel = sel[sel[k] == v]
    return sel.iloc[0] if len(sel) else None


def _xsens_analogue(summary, nominal, params) -> str:
    s = _row(summary, recording="xsens_mti", estimator="full_lls")
    if s is None:
        return "no Xsens full-LLS result in this run"
    nom = nominal[(nominal.recording == "xsens_mti") & (nominal.estimator == "full_lls")]
    rel = ", ".join(f"{r.rel_diff_pct:+.2f}%" for r in nom.itertuples())
    full = params[(params.recording == "xsens_mti") & params.estimator.map(model_of).eq("full")]
    spread = full.groupby("parameter")["value"].agg(lambda v: v.max() - v.min())
    within = full.groupby("parameter")["boot_se"].min()
    ratio = float(np.nanmax(spread / within)) if len(spread) else float("nan")
    return (f"public analogue, Xsens MTi (IMU-TK example, {int(s.n_poses)} hand-placed poses, full LLS): "
            f"sensitivities {rel} from the nominal 415/413/415 counts per m/s^2; full LLS, ALS and NLLS agree to "
            f"{ratio:.2g} bootstrap standard errors; residual RMS {1e3 * s.residual_rms:.2f} mm/s^2 is "
            f"{s.excess:.1f}x what the pose noise explains (chi2/dof = {s.reduced_chi2:.1f}, dof {int(s.dof)}); "
            f"leave-one-pose-out RMS {1e3 * s.lopo_rms:.2f} mm/s^2 (results/measured/summary.csv, nominal.csv)")


def _imucal_analogue(summary, peer) -> str:
    s = _row(summary, recording="imucal_ferraris", estimator="bias_lls")
    if s is None or peer is None or len(peer) == 0:
        return "no imucal bias-only result in this run"
    sel = peer[(peer.poses == "section_list") & (peer.parameter == "bias") & (peer.method == "bias_lls")]
    db = float(np.max(np.abs(sel.diff_to_imucal))) if len(sel) else float("nan")
    k = peer[(peer.poses == "section_list") & (peer.parameter == "scale_factor") & (peer.tool == "imucal")]
    ks = ", ".join(f"{100 * v:+.2f}%" for v in k.value)
    return (f"public analogue, imucal Ferraris example (6 static positions, bias-only LLS with M = I): bias within "
            f"{1e3 * db:.2f} mm/s^2 of imucal's Ferraris bias on the same poses, but residual RMS "
            f"{1e3 * s.residual_rms:.0f} mm/s^2 ({s.excess:.0f}x the pose noise) because the unit's scale factors "
            f"({ks} by Ferraris) are not 0 as M = I assumes (results/measured/peer_imucal.csv, summary.csv)")


def measured_claims(summary: pd.DataFrame, params: pd.DataFrame, nominal: pd.DataFrame,
                    peer: pd.DataFrame | None = None) -> pd.DataFrame:
    """Ledger rows (:data:`accelcal_repro.claims.COLUMNS`) for the real-data results of the papers.

    Parameters
    ----------
    summary, params, nominal : DataFrame
        The stage's gathered tables (``results/measured/summary.csv`` etc.).
    peer : DataFrame, optional
        ``results/measured/peer_imucal.csv``.
    """
    xs = _xsens_analogue(summary, nominal, params)
    im = _imucal_analogue(summary, peer)
    no_data = "not reproducible: the paper's recordings are not public"
    rows = [
        Claim("burkhard2024", "table1_lab_full_lls",
              "Table 1, laboratory tests L1 (35 poses) and L2 (15 poses): full LLS gives scale factors, "
              "non-orthogonality and biases of four ADIS-16475 IMUs that are consistent among themselves and "
              "not far from the datasheet",
              "Table 1 (L1, L2)").not_reproducible(f"{no_data} (ADIS-16475 'dahu 0-3'); {xs}"),
        Claim("burkhard2024", "table1_field_bias_lls",
              "Table 1, field tests F1 and F2 on the TP-2 drone: bias-only LLS from six static poses (ADIS-16475 "
              "pre-corrected with the L1 scale and non-orthogonality; M = I assumed for the STIM318)",
              "Table 1 (F1, F2)").not_reproducible(f"{no_data} (ADIS-16475, STIM318 on TP-2); {im}"),
        Claim("batista2011", "sec6b_calibration_parameters",
              "Sec. VI-B: offline calibration of a Silicon Designs tri-axial accelerometer on an Ideal Aerosmith "
              "2103HT motion rate table gives F^-1, b' and F2, all within the manufacturer's specifications",
              "F^-1 = [[0.9946, 0.0037, -0.0061], [-0.0091, 0.9998, 0.0079], [-0.0071, -0.0186, 1.0047]]; "
              "b' = (-0.7368, -0.2803, 0.3995) m/s^2; F2 = 1e-4 diag(-2.362, 1.055, 3.666)").not_reproducible(
            f"{no_data}, and the method needs the table's known rotations R(t_i), which none of the public "
            f"recordings has (all hand-placed); {xs}"),
        Claim("batista2011", "sec6b_parameters_stable_bias_varies",
              "Sec. VI-B: over tests on different days, scale, cross-axis and quadratic terms do not change "
              "significantly while the bias changes greatly, even without a power cycle",
              "qualitative").not_reproducible(
            f"{no_data}; each public recording is a single session of its unit, so nothing can be said about "
            "day-to-day stability"),
        Claim("batista2011", "fig11_static_errors_nonzero",
              "Sec. VI-B, Fig. 11: after calibration the mean error at a static position is not always zero "
              "(higher-order nonlinearities and time-varying parameters)",
              "Fig. 11").not_reproducible(f"{no_data}; {xs}"),
    ]
    return validate_rows(pd.DataFrame(rows, columns=list(COLUMNS)), source="measured claims")


__all__ = ["measured_claims"]
