"""The cells of the gyro-unit property (tests/test_units_evidence.py): a format x the unit its gyro values are in
x whether the unit is declared, each read and calibrated as a user would, with its outcome.

:func:`outcome` writes one session (motions between rests, or for imucal's annotated format a Ferraris
session) in a format, its gyro in ``rad/s``, ``deg/s`` or raw ``counts``, the unit declared (a header unit,
``--gyro-unit``) or not (for a format whose spec fixes the unit: the spec), reads it with
:func:`accelcal.formats.read` and calibrates its gyro (:func:`accelcal.gyro.recording.calibrate_recording_gyro`).
The outcome is ``right`` (the calibrated rates match the truth within :data:`RIGHT`), ``refused`` (one line),
or ``WRONG xF`` (a silent factor F: the property fails).  ``python -m tests.units_cells`` prints the table.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from accelcal.errors import AccelcalError

UNITS = ("rad/s", "deg/s", "counts")
FORMATS = ("csv", "gyro-file", "mpu6050", "imucal", "imucal-annotated", "ros", "px4", "ardupilot")
#: Raw counts per rad/s of the counts cells (16.4 LSB per deg/s, an MPU-6050 at +-2000 deg/s).
COUNTS_PER_RAD_S = 16.4 * 180.0 / np.pi
#: Relative RMS error of the calibrated rates during the motions below which a cell is right.
RIGHT = 0.03
FS = 100.0
G = 9.81


def session(seed: int = 5) -> dict:
    """A multi-position session (10 motions between 11 rests) with its accelerometer calibration and poses."""
    from accelcal.calibration import calibrate_recording
    from accelcal.gyro.recording import MIN_RESTS
    from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording
    from accelcal.recording import Recording

    rng = np.random.default_rng(seed)
    s = simulate_recording(rng, n_motions=10, rest_s=1.5, init_rest_s=4.0, C=random_gyro_matrix(rng),
                           gyro_bias=[0.01, -0.02, 0.005], fs=FS, g=G)
    rec = Recording(s["t"], s["acc"], None, "truth", unit="m/s^2")
    s["acc_cal"], s["poses"] = calibrate_recording(rec, G, "full_lls", search=True, min_poses=MIN_RESTS)
    return s


def ferraris_session(seed: int = 6) -> dict:
    """Six holds along +-x, +-y, +-z, then one 360 deg turn about each axis (imucal's protocol)."""
    rng = np.random.default_rng(seed)
    ups = {"x_p": [1, 0, 0], "x_a": [-1, 0, 0], "y_p": [0, 1, 0], "y_a": [0, -1, 0], "z_p": [0, 0, 1],
           "z_a": [0, 0, -1]}
    parts, acc, rates = [], [], []
    for name, up in ups.items():
        parts += [name] * 150
        acc.append(np.tile(np.array(up, float) * G, (150, 1)))
        rates.append(np.zeros((150, 3)))
    for a, name in enumerate(("x_rot", "y_rot", "z_rot")):
        w = np.zeros((300, 3))
        w[:, a] = 2 * np.pi / 3.0
        up = np.eye(3)[a] * G  # the turn about the vertical axis: gravity stays put
        parts += [name] * 300
        acc.append(np.tile(up, (300, 1)))
        rates.append(w)
    rates = np.concatenate(rates)
    return {"t": np.arange(len(parts)) / FS, "acc": np.concatenate(acc) + 0.01 * rng.standard_normal((len(parts), 3)),
            "gyro": rates + [0.01, -0.02, 0.005] + 0.003 * rng.standard_normal(rates.shape), "rates": rates,
            "parts": np.array(parts)}


def in_unit(rad_s, unit: str) -> np.ndarray:
    """Gyro values in ``unit`` (counts: rounded, at :data:`COUNTS_PER_RAD_S`)."""
    if unit == "rad/s":
        return np.asarray(rad_s, float)
    if unit == "deg/s":
        return np.rad2deg(rad_s)
    return np.round(np.asarray(rad_s, float) * COUNTS_PER_RAD_S)


def write(fmt: str, s: dict, unit: str, declared: bool, folder: Path) -> tuple[Path, dict]:
    """The file of ``s`` in ``fmt`` with its gyro in ``unit``, and the keyword arguments of ``read``."""
    w = in_unit(s["gyro"], unit)
    t, acc = s["t"], s["acc"]
    option = {"gyro_unit": unit} if declared else {}
    path = folder / f"{fmt}.{'bag' if fmt == 'ros' else 'bin' if fmt in ('px4', 'ardupilot') else 'csv'}"
    if fmt == "csv":
        u = f" [{unit}]" if declared else ""
        header = "t,ax,ay,az," + ",".join(f"g{a}{u}" for a in "xyz")
        np.savetxt(path, np.column_stack([t, acc, w]), delimiter=",", header=header, comments="", fmt="%.10g")
        return path, {}
    if fmt == "gyro-file":  # IMU-TK's two files of t x y z; the unit, if any, by --gyro-unit
        g = folder / "gyro.txt"
        np.savetxt(path, np.column_stack([t, acc]), fmt="%.10g")
        np.savetxt(g, np.column_stack([t, w]), fmt="%.10g")
        return path, {"gyro": g, **option}
    if fmt == "mpu6050":
        counts = np.round(acc / 9.80665 * 16384.0)
        lines = [f"Fs,{FS:g}", "Logging Type,0", "Initialization time,6", "Waiting time,3", "ax,ay,az,gx,gy,gz"]
        lines += [",".join(f"{v:.10g}" for v in (*a, *g)) for a, g in zip(counts, w)]
        path.write_text("\n".join(lines) + "\n")
        return path, option
    if fmt == "imucal":
        lines = ["n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"]
        lines += [",".join([str(i), *(f"{v:.10g}" for v in (*g, *a))]) for i, (a, g) in enumerate(zip(acc, w))]
        path.write_text("\n".join(lines) + "\n")
        return path, {"rate": FS, **option}
    if fmt == "imucal-annotated":
        counts = np.round(acc / 9.80665 * 2048.0)
        lines = ["part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"]
        lines += [",".join([p, str(i), *(f"{v:.10g}" for v in (*a, *g))])
                  for i, (p, a, g) in enumerate(zip(s["parts"], counts, w))]
        path.write_text("\n".join(lines) + "\n")
        return path, {"rate": FS, **option}
    if fmt == "ros":
        from .ros_synthetic import write_imu_bag

        return write_imu_bag(path, 1.7e9 + t, acc, w, kind="ros1"), option
    if fmt == "px4":
        from .log_fixtures import write_ulog

        ts = (10**6 + np.round(t * 1e6)).astype(np.uint64)
        topics = {(name, 0): {"timestamp": ts + 40, "timestamp_sample": ts, "device_id": np.full(len(t), k, np.uint32),
                              **{a: v[:, j].astype(np.float32) for j, a in enumerate("xyz")}}
                  for k, (name, v) in enumerate((("sensor_accel", acc), ("sensor_gyro", w)))}
        return write_ulog(path, topics), option
    if fmt == "ardupilot":
        from .log_fixtures import write_dataflash

        return write_dataflash(path, (10**6 + np.round(t * 1e6)).astype(np.int64), acc, w), option
    raise ValueError(fmt)


class _NoAccelerometerModel:
    """A Ferraris session's gyro without a full accelerometer model: the nominal rotation axes."""

    model = "bias"


def outcome(fmt: str, unit: str, declared: bool, s: dict) -> str:
    """``right (...)``, ``refused: ...`` or ``WRONG xF`` of one cell (module docstring)."""
    from accelcal.formats import read
    from accelcal.gyro.recording import calibrate_recording_gyro

    with tempfile.TemporaryDirectory() as tmp:
        path, kwargs = write(fmt, s, unit, declared, Path(tmp))
        try:
            rec = read(path, **kwargs)
        except AccelcalError as e:
            return f"refused at reading: {str(e).splitlines()[0]}"
        ferraris = fmt == "imucal-annotated"
        try:
            g = calibrate_recording_gyro(rec, _NoAccelerometerModel() if ferraris else s["acc_cal"],
                                         None if ferraris else s["poses"], g_sensitivity=False)
        except AccelcalError as e:
            return f"refused: {str(e).splitlines()[0]}"
    w = g.model.correct(rec.gyro)
    moving = np.linalg.norm(s["rates"], axis=1) > 0.2
    err = np.linalg.norm(w[moving] - s["rates"][moving]) / np.linalg.norm(s["rates"][moving])
    if err < RIGHT:
        return f"right ({g.model.raw_unit}, {g.settings.get('nominal_from', '')[:40]}; rms error {100 * err:.2g} %)"
    factor = np.median(np.linalg.norm(w[moving], axis=1) / np.linalg.norm(s["rates"][moving], axis=1))
    return f"WRONG x{factor:.3g} (rms error {100 * err:.3g} %)"


def static_session(seed: int = 7, n: int = 1000) -> dict:
    """A static record (one orientation, the gyro at rest with a bias): no motion decides a unit."""
    rng = np.random.default_rng(seed)
    gyro = [0.004, -0.003, 0.002] + 0.002 * rng.standard_normal((n, 3))
    acc = [0.2, -0.1, G] + 0.01 * rng.standard_normal((n, 3))
    parts = np.array(["z_p"] * n)
    return {"t": np.arange(n) / FS, "acc": acc, "gyro": gyro, "rates": np.zeros((n, 3)), "parts": parts}


def static_outcome(fmt: str, unit: str, declared: bool, s: dict) -> str:
    """What the noise analysis gets of a static record's gyro: ``right`` (the rates in rad/s, or raw counts
    said to be counts), ``refused: ...`` (one line), or ``WRONG xF``."""
    from accelcal.formats import read
    from accelcal.formats.units_evidence import require_gyro_unit

    with tempfile.TemporaryDirectory() as tmp:
        path, kwargs = write(fmt, s, unit, declared, Path(tmp))
        try:
            rec = read(path, **kwargs)
            require_gyro_unit(rec, "a static record")
        except AccelcalError as e:
            return f"refused: {str(e).splitlines()[0]}"
    if rec.gyro_unit == "counts":
        truth = in_unit(s["gyro"], unit)
        return "right (counts)" if np.allclose(rec.gyro, truth, atol=1e-3) else "WRONG (counts of other values)"
    factor = float(np.median(np.abs(rec.gyro) / np.abs(s["gyro"])))
    return f"right ({rec.gyro_unit})" if abs(factor - 1) < 1e-3 else f"WRONG x{factor:.3g}"


def table() -> list[tuple[str, str, str, str]]:
    """Every cell: (format, unit, declared or not, outcome)."""
    s, f = session(), ferraris_session()
    return [(fmt, unit, "declared" if d else "undeclared", outcome(fmt, unit, d, f if fmt == "imucal-annotated"
                                                                      else s))
            for fmt in FORMATS for unit in UNITS for d in (True, False)]


def static_table() -> list[tuple[str, str, str, str]]:
    """Every static cell: (format, unit, declared or not, outcome)."""
    s = static_session()
    return [(fmt, unit, "declared" if d else "undeclared", static_outcome(fmt, unit, d, s))
            for fmt in FORMATS for unit in UNITS for d in (True, False)]


if __name__ == "__main__":
    for row in table():
        print(" | ".join(row))
    print("static records (the noise analysis):")
    for row in static_table():
        print(" | ".join(row))
