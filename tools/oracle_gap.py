"""What limits the wander loop's agreement with the oracle: power of one test with more or less of
the noise covariance known (issue 34, item 1).

On the pose designs the benchmark draws (detected poses of simulated recordings of a profile), the
linearised problem of the base fit is taken as given and contrast data are drawn from the profile's
true covariance, with and without the effect at its oracle MDE (level alpha/family, the configured
power).  The same likelihood-ratio statistic is computed with

* ``oracle``: the true covariance (chi2_k: the oracle's test);
* ``shape``: the true covariance up to a common scale s (F test);
* ``family``: the true member (its kernel) with s and its size q estimated (ML, q on the test grid);
* ``loop``: the loop's whole grid (flicker, placement, Gauss-Markov tau, random walk) at phi = 0;
* ``*_s_known``: the same with the white scale known (its true value in these contrasts).

The critical value of each statistic is its own (1 - alpha/family) quantile under the true null
(size-adjusted power: the best any calibration of that statistic can do), so the columns differ
only in how much the statistic knows about the covariance.

Usage: python tools/oracle_gap.py PROFILE EFFECT [designs] [draws]
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import yaml
from pathlib import Path

from accelcal.discrepancy import wander as C
from accelcal.discrepancy.fit import fit, pose_data_from_static
from accelcal.discrepancy.residuals import effect_columns
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.statistics import critical_noncentrality
from accelcal.discrepancy.wander_model import linearise
from accelcal.noise.terms import model_avar
from accelcal.static import detect_static_recording
from accelcal_repro.discrepancy.benchmark import Session, simulate_case
from accelcal_repro.discrepancy.profiles import build_profiles, pose_residual_covariance


def ml_min(prob, X, Y, qgrid):
    return C.profile(prob, X, Y, qgrid).ml_min()


def main(prof_name="flicker_1x", eid="bias_drift", n_designs=6, draws=2000, boot=0):
    cfg = yaml.safe_load(Path("config/config.yaml").read_text())["discrepancy"]
    bench = cfg["benchmark"]
    session = Session.from_config(bench["session"])
    rules = Rules.from_config(cfg["rules"])
    profiles = build_profiles([p for p in bench["profiles"] if p["name"] == prof_name], session)
    prof = profiles[prof_name]
    family = len(rules.candidates) + 1
    level = rules.alpha / family
    rows = []
    for rep in range(n_designs):
        rec, key = simulate_case("none", 1.0, 1000 + rep, seed=cfg["seed"], session=session, rules=rules,
                                 profile=prof)
        data = pose_data_from_static(detect_static_recording(rec), session.g, rec.acc, rec.rate)
        base = fit(data)
        prob = linearise(data, base, common=0.0)
        J1 = effect_columns(base.p, data, (), eid)
        Xe = prob.columns(J1)
        X0 = prob.X0
        X1 = np.hstack([X0, Xe])
        dur = data.t_end - data.t_start + 1.0 / session.rate
        w = -(base.J[:, :3] * base.sigma[:, None])
        S = pose_residual_covariance(prof, data.t_start, dur, np.round(dur * session.rate), session.rate, w)
        Lw = prob.L / prob.sigma[:, None]
        Sc = Lw.T @ S @ Lw                                 # true contrast covariance
        m, k = Sc.shape[0], Xe.shape[1]
        Lc = np.linalg.cholesky(Sc)
        W = np.linalg.inv(Lc)
        # oracle MDE along a random direction (the benchmark's sizing)
        rng = np.random.default_rng(rep)
        d = rng.standard_normal(k)
        d /= np.linalg.norm(d)
        Q0, _ = np.linalg.qr(W @ X0)
        Je = W @ Xe
        Jp = Je - Q0 @ (Q0.T @ Je)
        info = Jp.T @ Jp
        lam = critical_noncentrality(k, m - X0.shape[1] - k, level, rules.power)
        a = np.sqrt(lam / float(d @ info @ d)) * d
        Z0 = rng.standard_normal((draws, m)) @ Lc.T
        Z1 = Z0 + (Xe @ a)[None, :] * 1.0
        info, s_true, Sw = information(prof, data, prob, Sc, Lw, w, session)
        out = {"design": rep, "m": m, **info, "s_true": round(s_true, 3)}
        # oracle / shape
        for name in ("oracle", "shape"):
            stats = []
            for Y in (Z0, Z1):
                Yw = Y @ W.T
                r0 = Yw - (Yw @ Q0) @ Q0.T
                Q1, _ = np.linalg.qr(W @ X1)
                r1 = Yw - (Yw @ Q1) @ Q1.T
                c0, c1 = np.sum(r0 ** 2, 1), np.sum(r1 ** 2, 1)
                stats.append(c0 - c1 if name == "oracle" else (c0 - c1) / c1)
            out[name] = power(*stats, level)
        # the loop's statistics: ML profiled over s (clipped) and q (grid), members as given
        fam = C.tau_grid(prob.durations, prob.span)
        members = {"family": truth_members(prof, fam), "loop": fam}
        for name, taus in members.items():
            p = prob.with_taus(taus)
            st = [ml_min(p, X0, Y, C.Q_REL_GRID) - ml_min(p, X1, Y, C.Q_REL_GRID) for Y in (Z0, Z1)]
            out[name] = power(*st, level)
            # the same with the white scale known (its true value: what the rests could pin)
            st1 = [ml_known_s(p, X0, Y / np.sqrt(s_true)) - ml_known_s(p, X1, Y / np.sqrt(s_true)) for Y in (Z0, Z1)]
            out[f"{name}_s_known"] = power(*st1, level)
            # and with the true per-pose white variances too (the oracle's white part): the
            # problem rewritten in the contrasts that whiten it, s = 1
            pw = whitened(p, Sw)
            R = np.linalg.cholesky(np.linalg.inv(Sw)).T
            X1w = np.hstack([pw.X0, R @ Xe])
            st2 = [ml_known_s(pw, pw.X0, Y @ R.T) - ml_known_s(pw, X1w, Y @ R.T) for Y in (Z0, Z1)]
            out[f"{name}_white_known"] = power(*st2, level)
            if boot:
                for under in (0, 1):
                    pv = [boot_p(p, X0, X1, Y[:boot], under, rng) for Y in (Z0, Z1)]
                    out[f"{name}_boot{under}_size"] = float(np.mean(pv[0] <= level))
                    out[f"{name}_boot{under}_size_a"] = float(np.mean(pv[0] <= rules.alpha))
                    out[f"{name}_boot{under}_power"] = float(np.mean(pv[1] <= level))
        rows.append(out)
        print(out, flush=True)
    keys = [k for k in rows[0] if k not in ("design", "m")]
    print(prof_name, eid, "mean size-adjusted power at 1x oracle MDE over", len(rows), "designs, ", draws,
          "draws each:", {k: round(float(np.mean([r[k] for r in rows])), 3) for k in keys})


def whitened(p, Sw):
    """``p`` in the contrasts ``R y`` that whiten the true white part ``Sw`` (``RᵀR = Sw⁻¹``)."""
    R = np.linalg.cholesky(np.linalg.inv(Sw)).T
    q = dataclasses.replace(p, y=R @ p.y, X0=R @ p.X0, L=p.L @ R.T)
    return q.with_taus(p.taus) if p.common == p.common else q


def ml_known_s(p, X, Y):
    """Grid minimum of ``−2ℓ`` with the white scale known (``s = 1``: ``Y`` divided by the true one)."""
    sf = C.profile(p, X, Y, C.Q_REL_GRID)
    return (sf.quad + sf.logdet[None]).reshape(len(Y), -1).min(axis=1)


def boot_p(p, X0, X1, Y, under, rng, n_boot=199):
    """Parametric-bootstrap p-values of the LR of each row of ``Y``, the null simulated with the
    noise (member, q) fitted under model ``under`` (0: the null's columns, the loop's way; 1: the
    alternative's, which does not absorb the effect)."""
    X = (X0, X1)[under]
    sf = C.profile(p, X, Y, C.Q_REL_GRID)
    ml = sf.reml  # the loop's estimate of the null's noise: REML
    lr = ml_min(p, X0, Y, C.Q_REL_GRID) - ml_min(p, X1, Y, C.Q_REL_GRID)
    out = np.empty(len(Y))
    for b in range(len(Y)):
        t, kq = np.unravel_index(int(np.argmin(ml[b])), ml[b].shape)
        q = C.Q_REL_GRID[kq]
        V, lam = p.V[t], p.lam[t]
        Z = (rng.standard_normal((n_boot, p.m)) * np.sqrt(1 + q * lam)) @ V.T
        lrs = ml_min(p, X0, Z, C.Q_REL_GRID) - ml_min(p, X1, Z, C.Q_REL_GRID)
        out[b] = (1 + np.sum(lrs >= lr[b])) / (n_boot + 1)
    return out


def truth_members(prof, grid):
    """The grid members of the profile's own process (flicker, or its Gauss-Markov taus)."""
    out = []
    for term, values in prof.components:
        if term == "bias_instability":
            out.append(C.FLICKER)
        elif term == "random_walk":
            out.append(np.inf)
        elif term == "gauss_markov":
            out.append(float(values[0][1]))
    return np.array(out or [C.PLACEMENT], float)


def information(prof, data, prob, Sc, Lw, w, session):
    """Fisher information on the log of the wander's size (all its components scaled together)
    from the pose residuals (REML, the white part known) and from the rests' Allan variances
    at every octave (the white level known): what each source can say about the wander."""
    dur = data.t_end - data.t_start + 1.0 / session.rate
    white = dataclasses.replace(prof, components=(), placement=(0.0, 0.0, 0.0))
    Sw = Lw.T @ pose_residual_covariance(white, data.t_start, dur, np.round(dur * session.rate), session.rate, w) @ Lw
    Cw = Sc - Sw
    Si = np.linalg.inv(Sc)
    X = prob.X0
    P = Si - Si @ X @ np.linalg.solve(X.T @ Si @ X, X.T @ Si)
    PC = P @ Cw
    i_pose = 0.5 * float(np.trace(PC @ PC))
    ra = data.rests.full
    i_rest = 0.0
    for a in range(3):
        A_w = sum(model_avar({term: values[a]}, ra.taus, session.rate) for term, values in prof.components)
        A_w = A_w if np.ndim(A_w) else np.zeros(ra.taus.size)
        A = (prof.white[a] ** 2 + 1.0 / 12.0) / ra.m + A_w
        i_rest += float(np.sum(ra.dof[a] / 2 * (A_w / A) ** 2))
    # the true white scale of these contrasts (the detection's standard errors are not exact)
    return {"info_pose": round(i_pose, 2), "info_rest": round(i_rest, 2)}, float(np.trace(Sw)) / Sw.shape[0], Sw


def power(s0, s1, level):
    crit = np.quantile(s0, 1 - level)
    return float(np.mean(s1 > crit))


if __name__ == "__main__":
    a = sys.argv[1:]
    main(a[0] if a else "flicker_1x", a[1] if len(a) > 1 else "bias_drift", int(a[2]) if len(a) > 2 else 6,
         int(a[3]) if len(a) > 3 else 2000, int(a[4]) if len(a) > 4 else 0)
