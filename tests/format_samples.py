"""A small valid file of every registered format, for the conformance tests and the fuzzer.

``SAMPLES[name](rng)`` returns the bytes of a file of format ``name`` (a few poses of a
sensor at rest, in the format's own unit; the logs are written by rosbags' writer and
tests/log_fixtures.py); a format added to the registry needs one here
(tests/test_format_conformance.py fails until it has one).  Every sample holds
:data:`ROWS` samples, timed from 0 at :data:`RATE_HZ` where the file carries time.

``SAMPLES[name](rng, damage)`` writes the same file broken in one way every recording is
refused for (:data:`DAMAGES`: one row, a non-finite value, time that goes back), for
tests/test_recording_invariants.py: the reader writes it as it is, the check every
recording passes refuses it.
"""

from __future__ import annotations

import io

import numpy as np

#: Samples per file and their rate [Hz] (where the format writes time or a rate).
ROWS = 60
RATE_HZ = 100.0
#: Poses of every sample file (unit vectors; the sensor rests in each for a third of the file).
POSES = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
#: The ways a sample is broken (``damage=``): one sample only; a non-finite specific force at
#: sample :data:`BROKEN`; samples :data:`BROKEN` and the next one swapped in time.
DAMAGES = ("one_row", "nan", "backwards")
BROKEN = 7


def rows(damage=None) -> int:
    """The samples a file holds."""
    return 1 if damage == "one_row" else ROWS


def specific_force(rng, scale: float = 9.80665, damage=None) -> np.ndarray:
    """(n, 3) specific force of three rests, in ``scale`` units per g, with noise (``damage='nan'``:
    sample :data:`BROKEN`'s x is nan)."""
    pose = np.repeat(POSES, ROWS // len(POSES), axis=0)
    out = (scale * pose + 0.002 * scale * rng.standard_normal((ROWS, 3)))[:rows(damage)]
    if damage == "nan":
        out[BROKEN, 0] = np.nan
    return out


def times(damage=None, start: float = 0.0) -> np.ndarray:
    """The samples' times [s] at :data:`RATE_HZ` from ``start`` (``damage='backwards'``: two swapped)."""
    t = start + np.arange(rows(damage)) / RATE_HZ
    if damage == "backwards":
        t[[BROKEN, BROKEN + 1]] = t[[BROKEN + 1, BROKEN]]
    return t


def _number(v, fmt: str = "{:d}") -> str:
    """An integer count as written, or ``nan``."""
    return "nan" if np.isnan(v) else fmt.format(int(v))


def recording(rng):
    """A :class:`Recording` in m/s² with temperature and its three rests as known intervals."""
    from accelcal.recording import Recording

    third = ROWS // len(POSES)
    return Recording(np.arange(ROWS) / RATE_HZ, specific_force(rng), 21.0 + 0.01 * rng.standard_normal(ROWS),
                     "sample", intervals=[(k * third + 2, (k + 1) * third - 2) for k in range(len(POSES))],
                     labels=("z_up", "x_up", "y_down"))


def block_log(rng, damage=None) -> bytes:
    third = ROWS // len(POSES)
    lines = ["Sensor:       FXOS8700_A", "Type:         Acceleration (m/s2)", "x, y, z"]
    for k, block in enumerate(np.array_split(specific_force(rng, damage=damage), len(POSES))):
        lines += [f">>> Place accelerometer in pose {k}", ">>> Type key when ready...",
                  f">>> Gathering data for {third / RATE_HZ:g} seconds..."]
        lines += [", ".join(f"{v:.4f}" for v in row) for row in block]
        lines.append("--- Send line ending")
    return ("\r\n".join(lines) + "\r\n").encode()


def mpu6050(rng, damage=None) -> bytes:
    """No time in the file (``t = row / Fs``): ``damage='backwards'`` cannot be written."""
    acc = np.round(specific_force(rng, 16384.0, damage))
    gyro = rng.integers(-40, 40, (rows(damage), 3))
    lines = [f"Fs,{RATE_HZ:g}", "Logging Type,0", "Initialization time,0.2", "Waiting time,3", "ax,ay,az,gx,gy,gz"]
    lines += [",".join(_number(v) for v in (*a, *w)) for a, w in zip(acc, gyro)]
    return ("\n".join(lines) + "\n").encode()


def imucal(rng, damage=None) -> bytes:
    """Time is the counter over the rate: ``damage='backwards'`` swaps two counts."""
    acc, gyro = specific_force(rng, damage=damage), 0.1 * rng.standard_normal((rows(damage), 3))
    count = np.round(times(damage) * RATE_HZ).astype(int)
    lines = ["n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"]
    lines += [",".join([str(i), *(f"{v:.6f}" for v in (*w, *a))]) for i, a, w in zip(count, acc, gyro)]
    return ("\n".join(lines) + "\n").encode()


def imucal_annotated(rng, damage=None) -> bytes:
    """Grouped by section, not in time order (as imucal writes it): rests, then the rotation.  The
    rows are sorted by their sample numbers: ``damage='backwards'`` repeats one."""
    acc = np.round(specific_force(rng, 2048.0, damage))
    gyro = rng.integers(-20, 20, (rows(damage), 3))
    third = ROWS // len(POSES)
    part = np.repeat(np.array(["z_p", "x_p", "y_a"], dtype="<U5"), third)[:rows(damage)]
    part[third - 5:third + 5] = "x_rot"  # a rotation between the first two rests
    count = np.arange(rows(damage))
    if damage == "backwards":
        count[BROKEN + 1] = BROKEN
    order = np.argsort(part == "x_rot", kind="stable")  # the rotation rows last
    lines = ["part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"]
    lines += [",".join([part[i], str(count[i]), *(_number(v) for v in (*acc[i], *gyro[i]))]) for i in order]
    return ("\n".join(lines) + "\n").encode()


def csv(rng, damage=None) -> bytes:
    """The canonical CSV (the csv format's writer), with temperature and a pose column (a damaged
    one without the pose column; its nan written as ``nan``, where the writer leaves the field empty)."""
    import tempfile
    from dataclasses import replace
    from pathlib import Path

    from accelcal.formats import write_recording

    rec = recording(rng)
    if damage is not None:
        n, acc = rows(damage), specific_force(rng)
        acc[BROKEN, 0] = 12345.5 if damage == "nan" else acc[BROKEN, 0]
        rec = replace(rec, t=times(damage), acc=acc[:n], temp=rec.temp[:n], intervals=None, labels=None)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sample.csv"
        write_recording(path, rec)
        return path.read_bytes().replace(b"12345.5", b"nan")


def imutk(rng, damage=None) -> bytes:
    acc = specific_force(rng, 415.0, damage) + 32768.0
    out = io.StringIO()
    for t, row in zip(times(damage, 0.02984), acc):
        out.write("   " + "   ".join(f"{v:.7e}" for v in (t, *np.round(row))) + "\n")
    return out.getvalue().encode()


def _log_bytes(write) -> bytes:
    """The bytes of a log written by ``write(path)`` into a temporary folder."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        return write(Path(tmp) / "sample").read_bytes()


def _gyro(rng, damage=None) -> np.ndarray:
    return 0.01 * rng.standard_normal((rows(damage), 3))


def ros(rng, damage=None) -> bytes:
    """A ROS 1 bag (rosbags' writer) with one sensor_msgs/Imu topic, absolute header stamps."""
    from .ros_synthetic import write_imu_bag

    acc, gyro = specific_force(rng, damage=damage), _gyro(rng, damage)
    t = 1.7e9 + times()
    if damage == "backwards":  # swapped header stamps are a late message, sorted by the reader: a repeated one
        t[BROKEN + 1] = t[BROKEN]
    return _log_bytes(lambda p: write_imu_bag(p.with_suffix(".bag"), t, acc, gyro, kind="ros1"))


def px4(rng, damage=None) -> bytes:
    """A PX4 ULog with the raw sensor_accel and sensor_gyro (timestamps in µs).  ``damage='backwards'``:
    one sensor_accel stamp repeated (the writer orders the messages by time stamp), the gyro's intact."""
    from .log_fixtures import write_ulog

    acc, gyro = specific_force(rng, damage=damage), _gyro(rng, damage)
    n = rows(damage)
    ts = (10**6 + np.round(times(None if damage == "backwards" else damage) * 1e6)).astype(np.uint64)
    stamps = {"sensor_accel": ts.copy(), "sensor_gyro": ts}
    if damage == "backwards":
        stamps["sensor_accel"][BROKEN + 1] = ts[BROKEN]
    topics = {(name, 0): {"timestamp": stamps[name] + 40, "timestamp_sample": stamps[name],
                          "device_id": np.full(n, k, np.uint32),
                          **{a: v[:, j].astype(np.float32) for j, a in enumerate("xyz")}}
              for k, (name, v) in enumerate((("sensor_accel", acc), ("sensor_gyro", gyro)))}
    return _log_bytes(lambda p: write_ulog(p, topics))


def ardupilot(rng, damage=None) -> bytes:
    """An ArduPilot DataFlash log of IMU messages."""
    from .log_fixtures import write_dataflash

    acc, gyro = specific_force(rng, damage=damage), _gyro(rng, damage)
    return _log_bytes(lambda p: write_dataflash(p, (10**6 + np.round(times(damage) * 1e6)).astype(np.int64), acc,
                                                gyro))


def _gyro_deg_s(rng, damage=None) -> np.ndarray:
    """A gyro at rest in deg/s, biased enough that its unit is read from the values (>= 10 deg/s)."""
    return np.array([12.0, -3.0, 5.0]) + 0.2 * rng.standard_normal((rows(damage), 3))


def mat(rng, damage=None) -> bytes:
    """A MATLAB v5 file (SciPy's savemat): a struct of named vectors t_s, ax_mps2..az_mps2,
    gx_dps..gz_dps (units in the names), and a char variable that is not a recording."""
    import scipy.io

    acc, gyro = specific_force(rng, damage=damage), _gyro_deg_s(rng, damage)
    cols = {"t_s": times(damage), **{f"a{a}_mps2": acc[:, j] for j, a in enumerate("xyz")},
            **{f"g{a}_dps": gyro[:, j] for j, a in enumerate("xyz")}}
    out = io.BytesIO()
    scipy.io.savemat(out, {"imu": {k: v[:, None] for k, v in cols.items()}, "sensor": "test unit"})
    return out.getvalue()


def rda(rng, damage=None) -> bytes:
    """An R data file (rdata's writer, gzip): a data frame 't [s]', 'ax [m/s^2]'.., 'gx [deg/s]'.."""
    import tempfile
    from pathlib import Path

    import pandas as pd
    import rdata

    acc, gyro = specific_force(rng, damage=damage), _gyro_deg_s(rng, damage)
    df = pd.DataFrame({"t [s]": times(damage), **{f"a{a} [m/s^2]": acc[:, j] for j, a in enumerate("xyz")},
                       **{f"g{a} [deg/s]": gyro[:, j] for j, a in enumerate("xyz")}})
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sample.rda"
        rdata.write_rda(path, {"imu": df})
        return path.read_bytes()


SAMPLES = {"block-log": block_log, "mpu6050": mpu6050, "imucal": imucal, "imucal-annotated": imucal_annotated,
           "csv": csv, "imutk": imutk, "ros": ros, "px4": px4, "ardupilot": ardupilot, "mat": mat, "rda": rda}
