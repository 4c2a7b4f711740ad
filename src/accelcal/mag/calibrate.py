"""A session's magnetometer: the ellipsoid from every sample, the noise from the rests, the
alignment to the accelerometer and the dip from the rests (or from samples whose specific
force is close to g), and the trust lines.

>>> from accelcal.mag import calibrate_magnetometer
>>> mcal = calibrate_magnetometer(mag, raw_unit="gauss", acc_cal=cal, poses=poses)
>>> print(mcal.summary())
>>> mcal.model.correct(mag)        # unit field (or µT), in the accelerometer's frame
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import distributions as dist  # scipy.stats would cost ~1 s at import
from .align import MIN_DIRECTIONS, align
from .errors import MagDisturbanceError

from .fit import FieldSamples, fit_hard_iron, with_residual_covariance
from .model import MagModel, sym_from_vec
from .registry import mag_estimator
from .result import MagCalibration, spreads
from .trust import check_coverage, disturbed_rests, prepare, quiet_intervals, rest_noise

#: Relative tolerance on |specific force| for samples that stand in for rests (sessions without rests).
G_TOLERANCE = 0.02


def _n_independent(m, intervals) -> float | None:
    """Effective number of independent samples from the lag-1 autocorrelation of the rests'
    noise (a low-passed magnetometer's samples are not independent)."""
    rho = []
    for a, b in intervals:
        seg = m[a:b] - m[a:b].mean(axis=0)
        if len(seg) > 10:
            num = np.sum(seg[1:] * seg[:-1], axis=0)
            den = np.sum(seg * seg, axis=0)
            rho.append(np.where(den > 0, num / np.maximum(den, 1e-300), 0.0))
    if not rho:
        return None
    r = float(np.clip(np.mean(rho), 0.0, 0.99))
    return len(m) * (1 - r) / (1 + r)


def calibrate_magnetometer(mag, *, raw_unit: str = "unknown", acc_cal=None, poses=None, acc=None,
                           estimator: str = "ellipsoid_ml", field=None, source: str = "magnetometer",
                           g_tolerance: float = G_TOLERANCE) -> MagCalibration:
    """Calibrate the magnetometer of one session.

    Parameters
    ----------
    mag : array_like (n, 3)
        Raw field samples, one per accelerometer sample (same rows).
    raw_unit : str
    acc_cal : Calibration, optional
        The accelerometer's calibration of the same session: its rests' specific force aligns
        the magnetometer (with ``poses``).
    poses : StaticPoses, optional
        The accelerometer's rests (sample ranges of the same rows): the noise and the alignment.
    acc : array_like (n, 3), optional
        Raw accelerometer samples: without rests, the samples whose |specific force| is within
        ``g_tolerance`` of its median stand in for them (the alignment then uses them raw,
        or through ``acc_cal`` when given).
    estimator : str
        A :data:`accelcal.mag.registry.MAG_ESTIMATORS` name.
    field : dict, optional
        ``{'strength': F, 'unit': 'uT', 'dip_deg': I, 'source': ...}`` from a geomagnetic model;
        without it the output is normalised to the fitted strength.
    """
    m_all = np.asarray(mag, dtype=float)
    prep = prepare(m_all, source)
    notes = list(prep.notes)
    rows = np.flatnonzero(prep.keep)
    m = prep.m
    intervals = _rests_in_kept_rows(poses, rows) if poses is not None else []
    if not intervals:
        intervals = quiet_intervals(m)
        noise_where = "the quietest stretches of the field (no accelerometer rests)"
    else:
        noise_where = "the accelerometer's rests"
    cov, n_noise, how = rest_noise(m, intervals)
    how = f"{noise_where}: {how}" if cov is not None else "no rest: the s.e. from the fit's own residual"
    samples = FieldSamples(m, noise_cov=cov, noise_source=how, n_independent=_n_independent(m, intervals))
    est = mag_estimator(estimator)
    fit = with_residual_covariance(est.fit(samples), samples)
    A, b = fit.A, fit.b
    h = (m - b) @ A.T
    cover = check_coverage(h, source)
    disturbed = disturbed_rests(m, intervals, cov, 1.0 / float(np.mean(np.linalg.eigvalsh(A)))) if poses else []
    n_rests = len(intervals) if poses is not None else 0
    if poses is not None and disturbed and len(disturbed) > n_rests / 2:
        raise MagDisturbanceError(f"{source}: the field changes while the device rests in {len(disturbed)} of "
                                  f"{n_rests} rests (a disturbance: iron or a motor moving nearby); record again "
                                  "away from it, or pass --no-mag")
    alignment, f_dirs, h_dirs, align_how = _alignment(m, rows, fit, acc_cal, poses, intervals, disturbed, acc,
                                                      g_tolerance, notes)
    R = np.eye(3) if alignment is None else alignment.R
    strength, unit = 1.0, "normalised"
    if field is not None:
        strength, unit = float(field["strength"]), field.get("unit", "uT")
    else:
        notes.append("magnetometer: normalised to the fitted field strength (|m| = 1): give --location and "
                     "--date for µT from a geomagnetic model")
    model = MagModel(A=A, b=b, R=R, strength=strength, strength_unit=unit, raw_unit=raw_unit)
    trust = {"coverage": cover, "noise_source": how, "n_samples": int(samples.n),
             "chi2_dof": None if fit.chi2 is None else fit.chi2 / fit.dof,
             "disturbed_rests": [int(k) for k in disturbed], "alignment_from": align_how}
    trust.update(_soft_iron_test(samples, fit))
    if f_dirs is not None:
        trust.update(spreads(h_dirs @ R.T, f_dirs))
        trust["dip_spread_unaligned_deg"] = spreads(h_dirs, f_dirs)["dip_spread_deg"]
    if field is not None and alignment is not None and field.get("dip_deg") is not None:
        trust["dip_model_deg"] = float(field["dip_deg"])
    return MagCalibration(model=model, fit=fit, alignment=alignment, estimator=est.name, trust=trust,
                          notes=tuple(notes))


def _soft_iron_test(samples, fit) -> dict:
    """The nested test of a sphere (hard iron and one scale, 4 unknowns) against the full
    ellipsoid (9): F = (Δχ² / 5) / (χ²_full / dof), robust to a χ²/dof above 1."""
    if fit.n_parameters != 9:
        return {}
    sphere = fit_hard_iron(samples)
    full_c2, sph_c2 = fit.residual_rms**2 * samples.n, sphere.residual_rms**2 * samples.n
    if samples.noise_cov is not None:
        full_c2, sph_c2 = fit.chi2, float(sphere.chi2)
    F = max((sph_c2 - full_c2) / 5.0, 0.0) / max(full_c2 / fit.dof, 1e-300)
    return {"soft_iron_F": float(F), "soft_iron_p": float(dist.f_sf(F, 5, fit.dof))}


def _rests_in_kept_rows(poses, rows) -> list[tuple[int, int]]:
    """The accelerometer's rests in the index space of the kept magnetometer rows."""
    out = []
    for a, b in np.asarray(poses.intervals, dtype=int):
        lo, hi = np.searchsorted(rows, a), np.searchsorted(rows, b)
        if hi - lo >= 5:
            out.append((int(lo), int(hi)))
    return out


def _alignment(m, rows, fit, acc_cal, poses, intervals, disturbed, acc, tol, notes):
    """The alignment from the rests (or samples near g), and the directions it used."""
    A, b = fit.A, fit.b
    if poses is not None and acc_cal is not None and intervals:
        keep = [k for k in range(len(intervals)) if k not in disturbed]
        f = np.array([acc_cal.apply(np.asarray(poses.means)[k:k + 1])[0] for k in range(len(poses.means))])
        # the rests that survived the kept-rows mapping are in the same order as the poses
        f = f[:len(intervals)][keep]
        hm = np.array([m[a:bb].mean(axis=0) for a, bb in intervals])[keep]
        how = f"{len(keep)} rests"
    elif acc is not None:
        a = np.asarray(acc, dtype=float)[rows]
        if acc_cal is not None:
            a = acc_cal.apply(a)
        na = np.linalg.norm(a, axis=1)
        ref = float(np.median(na))
        sel = np.abs(na - ref) <= tol * ref
        f, hm = a[sel], m[sel]
        how = (f"{int(sel.sum())} samples with |specific force| within {100 * tol:g} % of its median (no rests; "
               + ("calibrated accelerometer)" if acc_cal is not None else "raw accelerometer: its errors stay in the alignment)"))
    else:
        return None, None, None, "none (magnetometer alone: no alignment, no dip)"
    if len(f) < MIN_DIRECTIONS:
        notes.append(f"magnetometer: {len(f)} rests/samples near g: too few to align it to the accelerometer")
        return None, None, None, f"none ({how}: too few)"
    h = (hm - b) @ A.T
    al = _with_fit_error(align(f, h), f, hm, fit)
    if al.undetermined:
        notes.append("magnetometer: the rests leave the alignment undetermined along "
                     + "; ".join(al.undetermined) + " (rotate about more axes)")
    return al, f, h, how


def _with_fit_error(al, f, hm, fit):
    """The dip's s.e. with the ellipsoid's error carried through (every rest's field moves
    with ``A`` and ``b`` together, so their error does not average out over the rests):
    ``g Σ gᵀ`` added, ``g`` the dip's derivative in the nine parameters (central differences)."""
    if fit.cov is None or fit.n_parameters != 9:
        return al
    th = fit.theta
    g = np.zeros(9)
    for i in range(9):
        eps = 1e-6 * max(abs(th[i]), 1e-12) + 1e-9 * np.max(np.abs(th))
        d = [align(f, (hm - t[:3]) @ sym_from_vec(t[3:]).T).dip_deg for t in (th + eps * np.eye(9)[i],
                                                                              th - eps * np.eye(9)[i])]
        g[i] = (d[0] - d[1]) / (2 * eps)
    return replace(al, se_dip_deg=float(np.sqrt(al.se_dip_deg**2 + g @ fit.cov @ g)))


__all__ = ["G_TOLERANCE", "calibrate_magnetometer"]
