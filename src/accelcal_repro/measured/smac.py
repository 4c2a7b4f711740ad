"""Reader of the SMAC-Group ``imudata`` R data files (the 2.78 h static ADIS16405 recording).

``adis_16405_imu1.rda`` (``shared/data/README.md``) is an xz-compressed R data file
holding one object, a 1,000,000 × 6 numeric matrix of R class ``imu`` with columns
``Gyro. X/Y/Z`` (deg/s) and ``Accel. X/Y/Z`` (g), sampled at 100 Hz, the sensor at one
orientation (``Accel. Z`` ≈ −1.016 g).  The accelerometer columns are multiples of the
ADIS16405's output step of 3.33 mg.  The file carries no time column: ``t = i / fs``.

Read with the ``rdata`` package (the ``workflow`` extra; the core library does not
depend on it).  It is a recording of one orientation, so it is not a calibration source
of the measured stage (:mod:`accelcal_repro.measured.sources`, which calibrates poses):
the discrepancy stage uses it as the reference for slow bias wander
(:mod:`accelcal_repro.discrepancy.adis`), the noise stage for its noise terms against the
datasheet (:func:`read_smac_imu`: both sensors, SI units).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from accelcal.errors import RecordingError
from accelcal.recording import Recording
from accelcal.units import G0

#: The recording's sampling rate [Hz] (SMAC-Group imudata documentation of ``adis_16405_imu1``).
ADIS16405_RATE = 100.0
ACCEL_COLUMNS = ("Accel. X", "Accel. Y", "Accel. Z")
GYRO_COLUMNS = ("Gyro. X", "Gyro. Y", "Gyro. Z")


def read_smac_rda(path, fs: float = ADIS16405_RATE) -> Recording:
    """The accelerometer of a SMAC ``imudata`` ``.rda`` file as a :class:`Recording` (unit g).

    Parameters
    ----------
    path : path-like
        The ``.rda`` file.
    fs : float
        Sampling rate [Hz] (the file has no time column).

    Raises
    ------
    RecordingError
        One line naming the file: not readable as R data, no matrix, no accelerometer
        columns, non-finite values.
    """
    path, name, cols, values = _read_matrix(path, ACCEL_COLUMNS)
    acc = _columns(path, name, cols, values, ACCEL_COLUMNS, "accelerometer")
    return Recording(np.arange(len(acc)) / float(fs), acc, None, f"{path}:{name}")


def read_smac_imu(path, fs: float = ADIS16405_RATE) -> Recording:
    """Accelerometer and gyroscope of a SMAC ``imudata`` ``.rda`` file in SI units: ``Accel.``
    [g] × 9.80665 → m/s², ``Gyro.`` [deg/s] → rad/s; ``t = i / fs``.  Errors as :func:`read_smac_rda`."""
    path, name, cols, values = _read_matrix(path, ACCEL_COLUMNS + GYRO_COLUMNS)
    acc = _columns(path, name, cols, values, ACCEL_COLUMNS, "accelerometer") * G0
    gyro = np.radians(_columns(path, name, cols, values, GYRO_COLUMNS, "gyroscope"))
    notes = (f"SMAC-Group imudata {name}: Accel. X/Y/Z in g (x {G0}), Gyro. X/Y/Z in deg/s (to rad/s), "
             f"t = i / {fs:g} Hz",)
    return Recording(np.arange(len(acc)) / float(fs), acc, None, f"{path}:{name}", notes=notes, unit="m/s^2",
                     gyro=gyro, gyro_unit="rad/s")


def _read_matrix(path, needed):
    """(path, object name, column names, values) of the one matrix of an R data file."""
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        import rdata
    except ImportError:  # pragma: no cover (rdata is in the workflow extra)
        raise RecordingError(f"{path}: reading R data needs the 'rdata' package (pip install 'accelcal[workflow]')")
    try:
        with warnings.catch_warnings():  # "missing constructor for R class imu": the matrix is what we want
            warnings.simplefilter("ignore")
            objs = rdata.conversion.convert(rdata.parser.parse_file(path))
    except Exception as e:  # rdata raises many types on a damaged file
        raise RecordingError(f"{path}: not a readable R data file ({type(e).__name__}: {str(e)[:80]})") from None
    if len(objs) != 1:
        raise RecordingError(f"{path}: expected one object, found {len(objs)} ({', '.join(map(str, objs))})")
    (name, obj), = objs.items()
    values = np.asarray(obj, dtype=float)
    try:
        cols = [str(c) for c in obj.coords[obj.dims[1]].values]
    except (AttributeError, IndexError, KeyError):
        raise RecordingError(f"{path}: object {name!r} is not a matrix with column names") from None
    if values.ndim != 2:
        raise RecordingError(f"{path}: object {name!r} is not a matrix (shape {values.shape})")
    return path, name, cols, values


def _columns(path, name, cols, values, names, what):
    missing = [c for c in names if c not in cols]
    if missing:
        raise RecordingError(f"{path}: object {name!r} lacks {what} columns {missing} (has {cols})")
    x = values[:, [cols.index(c) for c in names]]
    if not np.all(np.isfinite(x)):
        raise RecordingError(f"{path}: non-finite {what} values")
    return x


__all__ = ["ACCEL_COLUMNS", "ADIS16405_RATE", "GYRO_COLUMNS", "read_smac_imu", "read_smac_rda"]
