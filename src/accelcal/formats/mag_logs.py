"""The magnetometer of a log (ROS ``sensor_msgs/MagneticField``, PX4 ``sensor_mag``, ArduPilot
``MAG``) put on the rows of the IMU's recording.

Alignment.  A log's magnetometer has its own messages and times, usually at a lower rate
than the IMU (10–100 Hz against 100–1000 Hz).  Each magnetometer sample is *held with its
own time*: placed on the one IMU row nearest its stamp, the rows between two samples left
empty (NaN, which the magnetometer's fit drops: :func:`accelcal.mag.trust.prepare`).  It is
not interpolated to the IMU's rows because the estimators count samples: the ellipsoid's
χ² and standard errors (:mod:`accelcal.mag.fit`) and the noise measured at the rests
(:func:`accelcal.mag.trust.rest_noise`) take each row as one measurement with the sensor's
noise; interpolated rows would repeat each sample 2–20 times with a smaller, correlated
noise, shrinking the standard errors by the square root of the rate ratio and the measured
noise by up to half.  What the estimators need from the time is only which rest (or which
near-g sample of a hand rotation) a field sample belongs to, for which the nearest IMU row
(at most half an IMU period away: 1–5 ms) is exact enough.

Time bases.  The magnetometer is timed by the same clock rule as the IMU (the sensor's
stamps, or the log's record times with ``--time-source log``).  Stamps that do not overlap
the IMU's, or (ROS) whose offset from the bag's record times differs from the IMU's by more
than :data:`MAX_BASE_OFFSET_S`, are on another time base: the magnetometer is then not read,
and the recording carries one note starting with :data:`MAG_WARNING` naming the cause and the
option (``accelcal calibrate`` keeps the accelerometer and gyro with that line;
``accelcal mag`` refuses in it, exit 2).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

#: The note that says why a log's magnetometer was not read (cause; option).
MAG_WARNING = "warning: magnetometer: "
#: Two stamp sets whose offsets from one reference clock differ by more than this are on different time bases
#: (the limit :mod:`accelcal.formats.sync` uses for two sensors of one table).
MAX_BASE_OFFSET_S = 0.25
#: Share of the shorter stream's span the two streams must overlap in.
MIN_OVERLAP = 0.5


class MagSkipped(Exception):
    """A log's magnetometer that cannot be read beside its IMU (the message is the cause and the option)."""


def mag_problem(rec) -> str | None:
    """The cause (and option) why a log's magnetometer was not read, or None."""
    return next((n[len(MAG_WARNING):] for n in rec.notes if n.startswith(MAG_WARNING)), None)


def skipped(rec, why: str):
    """``rec`` without magnetometer, and the one note that says why."""
    return replace(rec, mag=None, mag_unit=None, notes=rec.notes + (MAG_WARNING + why,))


def check_time_base(imu_s: np.ndarray, mag_s: np.ndarray, what: str, fix: str) -> None:
    """Refuse (:class:`MagSkipped`) magnetometer stamps that do not overlap the IMU's (all in seconds, one clock)."""
    lo, hi = max(imu_s[0], mag_s[0]), min(imu_s[-1], mag_s[-1])
    shorter = min(imu_s[-1] - imu_s[0], mag_s[-1] - mag_s[0])
    if not hi - lo >= MIN_OVERLAP * shorter or shorter <= 0:
        raise MagSkipped(f"{what} is on another time base than the IMU (its stamps {mag_s[0]:.6g}..{mag_s[-1]:.6g} s, "
                         f"the IMU's {imu_s[0]:.6g}..{imu_s[-1]:.6g} s: they overlap in {max(hi - lo, 0):.3g} s), so it "
                         f"cannot be aligned; {fix}")


def check_offsets(imu_off_s: float, mag_off_s: float, what: str, fix: str) -> None:
    """Refuse two streams whose stamps sit at different offsets from one reference clock (ROS: the bag's)."""
    if abs(imu_off_s - mag_off_s) > MAX_BASE_OFFSET_S:
        raise MagSkipped(f"{what} is on another time base than the IMU (stamped {mag_off_s - imu_off_s:+.3g} s from "
                         f"the IMU's stamps against the log's record time, more than {MAX_BASE_OFFSET_S:g} s), so it "
                         f"cannot be aligned; {fix}")


def place(imu_s, mag_s, field, what: str) -> tuple[np.ndarray, str]:
    """The field on the IMU's rows (module docstring): each sample on the row nearest its stamp,
    NaN elsewhere; and the note that says so.  ``imu_s``, ``mag_s``: one clock, seconds."""
    imu_s, mag_s, field = np.asarray(imu_s, float), np.asarray(mag_s, float), np.asarray(field, float)
    order = np.argsort(mag_s, kind="stable")
    mag_s, field = mag_s[order], field[order]
    right = np.clip(np.searchsorted(imu_s, mag_s), 1, len(imu_s) - 1)
    row = np.where(mag_s - imu_s[right - 1] <= imu_s[right] - mag_s, right - 1, right)
    gap = np.abs(imu_s[row] - mag_s)
    period = float(np.median(np.diff(imu_s)))
    inside = gap <= period  # samples beyond the IMU's span by more than one period have no row
    idx = np.flatnonzero(inside)
    by_row = idx[np.lexsort((gap[idx], row[idx]))]  # per row, the nearest sample first (ties: the earlier)
    keep = np.zeros(len(mag_s), bool)
    keep[by_row[np.r_[True, row[by_row][1:] != row[by_row][:-1]]]] = True
    out = np.full((len(imu_s), 3), np.nan)
    out[row[keep]] = field[keep]
    n, k = len(mag_s), int(keep.sum())
    rate = (n - 1) / (mag_s[-1] - mag_s[0]) if n > 1 and mag_s[-1] > mag_s[0] else float("nan")
    note = (f"{what}: {n} samples at {rate:.4g} Hz, each held on the IMU row nearest its stamp (at most "
            f"{1e3 * float(gap[keep].max()) if k else 0:.2g} ms away; the rows between samples hold none)")
    if k < n:
        note += (f"; {n - k} sample(s) left out ({int((~inside).sum())} outside the IMU's span, "
                 f"{int((inside & ~keep).sum())} sharing a row with a nearer one: the magnetometer is faster than the IMU)")
    return out, note


def attach(rec, imu_s, mag_s, field_uT, what: str, fix: str, extra_notes=()):
    """``rec`` with the magnetometer (µT) on its rows, or without it and one warning note (:class:`MagSkipped`)."""
    try:
        check_time_base(np.asarray(imu_s, float), np.sort(np.asarray(mag_s, float)), what, fix)
        rows, note = place(imu_s, mag_s, field_uT, what)
    except MagSkipped as e:
        return skipped(rec, str(e))
    return replace(rec, mag=rows, mag_unit="uT", notes=rec.notes + (note, *extra_notes))


__all__ = ["MAG_WARNING", "MagSkipped", "attach", "check_offsets", "check_time_base", "mag_problem", "place",
           "skipped"]
