"""Rotations of known angle found in the gyro alone, and the gyro calibrated from them.

A rate table (or a hand on a table) turns the sensor by a known angle about one axis
between two rests, once about each axis; the runs may be recorded apart (the CTU rig: one
``.mat`` variable per axis) or in one record.  Nothing marks where a rotation is, and
there may be no accelerometer: the gyro says it.

Rests and rotations, per run (:func:`find_rotations`):

1. the run's quietest :data:`REFERENCE_S` (the least mean ``|ω|²``: a rate gyro's bias
   is small beside a turn) gives a first bias and the noise of a moving mean of
   :data:`SMOOTH_S`;
2. the sensor turns where that moving mean departs from the first bias by more than
   :data:`THRESHOLD` of its noise; turns less than :data:`MERGE_S` apart are one motion;
3. the rests are the still stretches between motions (:data:`MIN_REST_S` or longer,
   :data:`TRIM_S` cut at each end); the run's bias is their weighted mean
   (:func:`accelcal.gyro.rests.fit_bias`), each run its own: a gyro's turn-on bias
   differs from run to run (CTU: by up to 0.19 °/s, 0.5 % of a turn's sum);
4. a motion that turns by :data:`MIN_ROTATION_DEG` or more by the nominal scale is a
   rotation; its integration window reaches :data:`PAD_S` into the rests around it (the
   bias is removed: the rests add only noise, and no slow start is cut off).

The fit is :func:`accelcal.gyro.ferraris.fit_ferraris` with each rotation's axis and its
run's bias and bias variance: three rotations, one about each axis, determine the nine
parameters exactly.  The axis is the nominal one (the rotation's largest component: the
frame is then that of the rotation axes), or, with a full accelerometer calibration, the
gravity direction during the rotation when the data show a turn about the vertical (the
calibrated specific force keeps its direction within :data:`VERTICAL_TOLERANCE_DEG`
throughout the window): the frame is then the accelerometer's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .rests import accel_directions
from .errors import NoMotionError, RotationAngleError, TooFewMotionsError
from .ferraris import N_ROTATIONS, ferraris_calibration, fit_ferraris
from .model import RAW_UNITS
from .rests import fit_bias, rest_noise, rest_statistics, sample_interval

#: Length of the quiet stretch that gives each run's first bias and noise [s].
REFERENCE_S = 2.0
#: Moving mean whose departure from the first bias marks a motion [s].
SMOOTH_S = 0.25
#: Departure, in standard deviations of that moving mean at rest, that is motion.
THRESHOLD = 8.0
#: Motions closer than this are one [s].
MERGE_S = 1.0
#: Shortest rest kept [s], and what is cut from its ends next to motion [s].
MIN_REST_S, TRIM_S = 1.0, 0.25
#: Smallest turn taken for a rotation of known angle [deg] (by the nominal scale).
MIN_ROTATION_DEG = 30.0
#: How far the integration window reaches into the rests around a rotation [s].
PAD_S = 0.5
#: Largest angle [deg] between the 0.5 s means of the specific force during a rotation and
#: their mean for the turn to be about the vertical (its axis then measured by gravity).
VERTICAL_TOLERANCE_DEG = 3.0


@dataclass(frozen=True)
class Rotation:
    """One rotation found in the gyro."""

    run: int
    window: tuple[int, int]  #: integration window [start, stop), sample indices of the recording
    motion: tuple[int, int]  #: where the sensor turns
    axis: int  #: its largest component (0, 1, 2: x, y, z)
    nominal_deg: float  #: its angle by the nominal scale, bias removed


@dataclass(frozen=True)
class RunRests:
    """The rests of one run and the bias they give."""

    run: tuple[int, int]
    intervals: np.ndarray  #: (p, 2) [start, stop)
    bias: np.ndarray  #: (3,)
    bias_se: np.ndarray  #: (3,) inflated by the rests' scatter when it exceeds their errors
    noise: np.ndarray  #: (3,) per-sample variance for sums (raw unit²)
    excess: float  #: scatter of the run's rest means about its bias, in their errors (nan: one rest)


def _segments(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of the runs of True."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def _moving_mean(x: np.ndarray, m: int) -> np.ndarray:
    """Centred moving mean of ``m`` samples (shorter at the ends)."""
    c = np.concatenate([np.zeros((1, x.shape[1])), np.cumsum(x, axis=0)])
    i = np.arange(len(x))
    lo, hi = np.clip(i - m // 2, 0, len(x)), np.clip(i - m // 2 + m, 0, len(x))
    return (c[hi] - c[lo]) / (hi - lo)[:, None]


def _motions(g: np.ndarray, h: float) -> list[tuple[int, int]]:
    """Where one run's sensor turns (steps 1-2 of the module docstring), run-relative."""
    n = len(g)
    w = int(min(max(round(REFERENCE_S / h), 10), max(n // 4, 10)))
    m = int(max(round(SMOOTH_S / h), 3))
    c = np.concatenate([[0.0], np.cumsum(np.sum(g * g, axis=1))])
    i0 = int(np.argmin(c[w:] - c[:-w]))
    ref = g[i0:i0 + w]
    b0 = ref.mean(axis=0)
    mm = _moving_mean(g - b0, m)
    sd = np.std(_moving_mean(ref - b0, m)[m:-m] if w > 3 * m else mm[i0:i0 + w], axis=0)
    sd = np.maximum(sd, 1e-12 * max(float(np.abs(g).max()), 1e-300))
    moving = np.max(np.abs(mm) / sd, axis=1) > THRESHOLD
    segs = _segments(moving)
    merged: list[tuple[int, int]] = []
    for a, b in segs:
        if merged and a - merged[-1][1] < MERGE_S / h:
            merged[-1] = (merged[-1][0], b)
        else:
            merged.append((a, b))
    return [(max(a - m // 2, 0), min(b + m // 2, n)) for a, b in merged]


def find_rotations(t, gyro, runs=None, *, nominal: float, windows=None,
                   rest_intervals=None) -> tuple[list[Rotation], list[RunRests], list[str]]:
    """The rotations and each run's rests (module docstring).

    Parameters
    ----------
    t, gyro : array_like (n,), (n, 3)
        Time [s] and raw gyro samples.
    runs : array_like (k, 2), optional
        Runs recorded apart (:attr:`~accelcal.recording.Recording.runs`); default one.
    nominal : float
        Nominal rad/s per raw unit (the angle of a motion, to tell rotations from jolts).
    windows : sequence of (start, stop), optional
        The rotations' integration windows as given (a section list's ``*_rot``), instead
        of those found; each inside one run.
    rest_intervals : array_like (p, 2), optional
        The rests as given (a section list's other sections), instead of those found.

    Returns
    -------
    rotations, rests per run, notes (motions too small to be rotations)
    """

    t, gyro = np.asarray(t, float), np.asarray(gyro, float)
    runs = np.array([[0, len(t)]]) if runs is None else np.asarray(runs, int)
    rotations, rests, notes = [], [], []
    for k, (a, b) in enumerate(runs):
        h = sample_interval(t[a:b]).h
        motions = _motions(gyro[a:b], h) if windows is None or rest_intervals is None else []
        rest = _run_rests(t, gyro, k, a, b, h, motions, rest_intervals)
        rests.append(rest)
        pad = int(round(PAD_S / h))
        spans = [(max(s - pad, 0), min(e + pad, b - a), s, e) for s, e in motions] if windows is None else \
            [(s - a, e - a, s - a, e - a) for s, e in windows if a <= s < b]
        for lo, hi, s, e in spans:
            if a + hi > b:
                raise RotationAngleError(f"the rotation window {a + lo}-{a + hi} spans two runs; each rotation lies "
                                         "inside one run (samples of the joined recording)")
            y = h * (gyro[a + lo:a + hi] - rest.bias).sum(axis=0)
            angle = float(np.rad2deg(abs(nominal) * np.linalg.norm(y)))
            when = f"run {k + 1}, t = {t[a + s] - t[a]:.3g}-{t[a + e - 1] - t[a]:.3g} s"
            if angle < MIN_ROTATION_DEG and windows is None:
                notes.append(f"a motion of {angle:.3g} deg ({when}) is not a rotation of known angle: left out")
                continue
            rotations.append(Rotation(k, (int(a + lo), int(a + hi)), (int(a + s), int(a + e)),
                                      int(np.argmax(np.abs(y))), angle))
    return rotations, rests, notes


def _run_rests(t, gyro, k: int, a: int, b: int, h: float, motions, given) -> RunRests:
    """One run's rests (given, or between its motions) and the bias they give (step 3)."""

    if given is not None:
        iv = np.asarray(given, dtype=np.int64).reshape(-1, 2)
        iv = iv[(iv[:, 0] >= a) & (iv[:, 1] <= b)]
    else:
        still = np.ones(b - a, bool)
        for s, e in motions:
            still[s:e] = False
        trim = int(round(TRIM_S / h))
        iv = [(s + trim * (s > 0), e - trim * (e < b - a)) for s, e in _segments(still)]
        iv = np.array([(a + s, a + e) for s, e in iv if e - s >= MIN_REST_S / h], dtype=np.int64).reshape(-1, 2)
    if len(iv) == 0:
        raise NoMotionError(f"run {k + 1} (samples {a}-{b}) has no rest" + (" among the given intervals" if given
                            is not None else f" of {MIN_REST_S:g} s or more") + ": a rotation of known angle needs "
                            "the sensor at rest around it (its bias)")
    rs = rest_statistics(t, gyro, iv)
    est = fit_bias(rs, "all")
    return RunRests((int(a), int(b)), iv, est.bias, est.bias_se * (max(1.0, est.excess) if len(iv) > 1 else 1.0),
                    rest_noise(rs), est.excess)


def angles_for(rotations: list[Rotation], angles_deg) -> np.ndarray:
    """The stated angle of each rotation: one for all, three by axis (x, y, z: each rotation
    takes its axis's), or one per rotation in time order."""
    a = np.atleast_1d(np.asarray(angles_deg, float))
    if a.size == 1:
        return np.full(len(rotations), float(a[0]))
    if a.size == 3:
        return a[[r.axis for r in rotations]]
    if a.size == len(rotations):
        return a
    raise RotationAngleError(f"{a.size} rotation angles for {len(rotations)} rotations: give one for all, three (one "
                             "per axis x, y, z) or one per rotation in time order (--rotation-angle)")


def measured_axes(rotations: list[Rotation], accel, acc, h: float):
    """The gravity direction of each rotation about the vertical (module docstring), its
    covariance, and notes on the rotations whose axis stays nominal (None for those)."""

    acc = np.asarray(acc, float)
    axes, covs, notes = [], [], []
    k = max(int(round(0.5 / h)), 1)
    for r in rotations:
        seg = acc[slice(*r.window)]
        blocks = seg[: len(seg) // k * k].reshape(-1, k, 3).mean(axis=1)
        u, cov, _ = accel_directions(accel, np.vstack([seg.mean(axis=0), blocks]),
                                     np.vstack([seg.std(axis=0, ddof=1) / np.sqrt(len(seg)), np.ones_like(blocks)]))
        spread = float(np.rad2deg(np.arccos(np.clip(u[1:] @ u[0], -1.0, 1.0))).max())
        if spread <= VERTICAL_TOLERANCE_DEG:
            axes.append(u[0])
            covs.append(cov[0])
        else:
            axes.append(None)
            covs.append(None)
            notes.append(f"the rotation about {'xyz'[r.axis]} tilts gravity by up to {spread:.3g} deg: not about the "
                         "vertical, its axis is taken as nominal")
    return axes, covs, notes


def calibrate_rotations(t, gyro, *, angles_deg, runs=None, raw_unit: str = "rad/s", nominal_sensitivity=None,
                        angle_std_deg: float = 0.0, source: str = "the recording", accel=None, acc=None,
                        windows=None, rest_intervals=None):
    """Calibrate a gyro from rotations of known angle found in it (module docstring).

    Parameters
    ----------
    t, gyro : array_like (n,), (n, 3)
        Time [s] and raw gyro samples (``raw_unit``: rad/s, or counts with ``nominal_sensitivity``).
    angles_deg : float or sequence
        The stated angles (:func:`angles_for`).
    runs : array_like (k, 2), optional
        Runs recorded apart, each with its own bias.
    nominal_sensitivity : float, optional
        Raw counts per rad/s.
    angle_std_deg : float
        Uncertainty of each stated angle [deg].
    accel, acc : optional
        A full accelerometer calibration (``apply(raw) -> m/s²``) and the raw accelerometer
        samples: rotations about the vertical get gravity as their axis (module docstring).
    windows, rest_intervals : optional
        The rotations' windows and the rests as given (:func:`find_rotations`).

    Returns
    -------
    GyroFerrarisCalibration
        In the frame of the rotation axes (nominal: the sensor's x, y, z), or the
        accelerometer's when every axis is measured; bias: the weighted mean of the runs'
        (each listed in ``settings['runs']``).
    """

    nominal = 1.0 / float(nominal_sensitivity) if nominal_sensitivity is not None else RAW_UNITS.get(raw_unit)
    if nominal is None:
        raise RotationAngleError("raw counts need the nominal gyro sensitivity (--gyro-sensitivity) to find the "
                                 "rotations and check their angles")
    t, gyro = np.asarray(t, float), np.asarray(gyro, float)
    rotations, rests, notes = find_rotations(t, gyro, runs, nominal=nominal, windows=windows,
                                             rest_intervals=rest_intervals)
    _check_coverage(rotations, source)
    angles = angles_for(rotations, angles_deg)
    h = float(np.mean([sample_interval(t[a:b]).h for a, b in (r.run for r in rests)]))
    segs = [gyro[slice(*r.window)] - rests[r.run].bias for r in rotations]
    noise = np.mean([r.noise for r in rests], axis=0)
    axes, axis_cov, notes = _axes(rotations, accel, acc, h, notes)
    fit = fit_ferraris(segs, h, angles, axes, nominal=nominal, y_var=noise,
                       bias_var=np.array([rests[r.run].bias_se ** 2 for r in rotations]), axis_cov=axis_cov,
                       angle_std_deg=angle_std_deg, names=tuple(f"{'xyz'[r.axis]} (run {r.run + 1})" for r in rotations))
    measured = axis_cov is not None
    bias, bias_se, warnings = session_bias(rests, raw_unit)
    settings = {"bias_mode": "per run" if len(rests) > 1 else "all", "angles_deg": angles.tolist(),
                "frame": "accelerometer frame" if measured else "rotation axes",
                "axes": axes.tolist() if measured else "nominal (each rotation's largest component)",
                "time_base": {"h": h, "rate": 1.0 / h, "jitter": None},
                "runs": [{"samples": list(r.run), "rests": r.intervals.tolist(), "bias": r.bias.tolist(),
                          "bias_se": r.bias_se.tolist(), "rest_excess": r.excess} for r in rests],
                "notes": notes}
    return ferraris_calibration(fit, bias, bias_se, raw_unit, nominal, nominal_axes=not measured, settings=settings,
                                motions=_motion_table(t, rotations, fit, angles), warnings=warnings)


def _axes(rotations: list[Rotation], accel, acc, h: float, notes):
    """The rotation axes measured by the accelerometer when every one is (with their covariance
    and the notes on those that are not), else the nominal ones (each rotation's largest
    component) and no covariance."""
    axes, axis_cov = np.eye(3)[[r.axis for r in rotations]], None
    if accel is not None and acc is not None:
        found, covs, axis_notes = measured_axes(rotations, accel, acc, h)
        notes = notes + axis_notes
        if all(a is not None for a in found):
            axes, axis_cov = np.array(found), np.array(covs)
    return axes, axis_cov, notes


def _motion_table(t, rotations: list[Rotation], fit, angles) -> dict:
    """The calibration's table of the rotations: times, integration window, run, axis, the
    angle the fit gives and the stated one."""
    return {"t_start": [float(t[r.motion[0]]) for r in rotations],
            "t_end": [float(t[r.motion[1] - 1]) for r in rotations],
            "window": [list(r.window) for r in rotations], "run": [r.run + 1 for r in rotations],
            "axis": ["xyz"[r.axis] for r in rotations], "angle_deg": fit.angles_deg.tolist(),
            "stated_deg": angles.tolist(), "used": [True] * len(rotations), "note": [""] * len(rotations)}


def _check_coverage(rotations: list[Rotation], source: str) -> None:
    """At least one rotation about each axis, else one line saying what was found."""

    if not rotations:
        raise NoMotionError(f"{source}: no rotation found (the gyro turns by less than {MIN_ROTATION_DEG:g} deg "
                            "throughout): a gyro without accelerometer is calibrated from rotations of known angle, one "
                            "about each axis; for the noise of a static record use accelcal noise")
    if len(rotations) < N_ROTATIONS or sorted({r.axis for r in rotations}) != [0, 1, 2]:
        found = ", ".join(f"{r.nominal_deg:.0f} deg about {'xyz'[r.axis]}" for r in rotations)
        raise TooFewMotionsError(f"{source}: rotations found: {found}; the gyro's 9 parameters need at least one about "
                                 "each of x, y and z (record the missing ones)")


def session_bias(rests: list[RunRests], raw_unit: str):
    """The bias stated for the session: the runs' weighted mean, its s.e. inflated by their
    scatter (turn-on biases differ), and a warning when they differ beyond their errors."""
    b = np.array([r.bias for r in rests])
    w = 1.0 / np.array([r.bias_se ** 2 for r in rests])
    bias = np.sum(w * b, axis=0) / np.sum(w, axis=0)
    chi2 = np.sum((b - bias) ** 2 * w, axis=0)
    bias_se = np.sqrt(1.0 / np.sum(w, axis=0)) * np.sqrt(np.maximum(1.0, chi2 / max(len(rests) - 1, 1)))
    warnings = [f"the runs' biases differ by up to {np.max(np.ptp(b, axis=0)):.3g} {raw_unit} (turn-on bias): each "
                "rotation had its own run's removed; the bias stated is their mean"] \
        if len(rests) > 1 and np.any(chi2 > 4 * (len(rests) - 1)) else []
    return bias, bias_se, warnings


__all__ = ["MIN_ROTATION_DEG", "VERTICAL_TOLERANCE_DEG", "Rotation", "RunRests", "angles_for", "calibrate_rotations",
           "find_rotations", "measured_axes", "session_bias"]
