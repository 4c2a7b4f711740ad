"""A small valid file of every registered format, for the conformance tests and the fuzzer.

``SAMPLES[name](rng)`` returns the bytes of a file of format ``name`` (a few poses of a
sensor at rest, in the format's own unit; the logs are written by rosbags' writer and
tests/log_fixtures.py); a format added to the registry needs one here
(tests/test_format_conformance.py fails until it has one).  Every sample holds
:data:`ROWS` samples, timed from 0 at :data:`RATE_HZ` where the file carries time.
"""

from __future__ import annotations

import io

import numpy as np

#: Samples per file and their rate [Hz] (where the format writes time or a rate).
ROWS = 60
RATE_HZ = 100.0
#: Poses of every sample file (unit vectors; the sensor rests in each for a third of the file).
POSES = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def specific_force(rng, scale: float = 9.80665) -> np.ndarray:
    """(ROWS, 3) specific force of three rests, in ``scale`` units per g, with noise."""
    pose = np.repeat(POSES, ROWS // len(POSES), axis=0)
    return scale * pose + 0.002 * scale * rng.standard_normal((ROWS, 3))


def recording(rng):
    """A :class:`Recording` in m/s² with temperature and its three rests as known intervals."""
    from accelcal.recording import Recording

    third = ROWS // len(POSES)
    return Recording(np.arange(ROWS) / RATE_HZ, specific_force(rng), 21.0 + 0.01 * rng.standard_normal(ROWS),
                     "sample", intervals=[(k * third + 2, (k + 1) * third - 2) for k in range(len(POSES))],
                     labels=("z_up", "x_up", "y_down"))


def block_log(rng) -> bytes:
    third = ROWS // len(POSES)
    lines = ["Sensor:       FXOS8700_A", "Type:         Acceleration (m/s2)", "x, y, z"]
    for k, block in enumerate(np.split(specific_force(rng), len(POSES))):
        lines += [f">>> Place accelerometer in pose {k}", ">>> Type key when ready...",
                  f">>> Gathering data for {third / RATE_HZ:g} seconds..."]
        lines += [", ".join(f"{v:.4f}" for v in row) for row in block]
        lines.append("--- Send line ending")
    return ("\r\n".join(lines) + "\r\n").encode()


def mpu6050(rng) -> bytes:
    acc = np.round(specific_force(rng, 16384.0)).astype(int)
    gyro = rng.integers(-40, 40, (ROWS, 3))
    lines = [f"Fs,{RATE_HZ:g}", "Logging Type,0", "Initialization time,0.2", "Waiting time,3", "ax,ay,az,gx,gy,gz"]
    lines += [",".join(str(v) for v in (*a, *w)) for a, w in zip(acc, gyro)]
    return ("\n".join(lines) + "\n").encode()


def imucal(rng) -> bytes:
    acc, gyro = specific_force(rng), 0.1 * rng.standard_normal((ROWS, 3))
    lines = ["n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"]
    lines += [",".join([str(i), *(f"{v:.6f}" for v in (*w, *a))]) for i, (a, w) in enumerate(zip(acc, gyro))]
    return ("\n".join(lines) + "\n").encode()


def imucal_annotated(rng) -> bytes:
    """Grouped by section, not in time order (as imucal writes it): rests, then the rotation."""
    acc = np.round(specific_force(rng, 2048.0)).astype(int)
    gyro = rng.integers(-20, 20, (ROWS, 3))
    third = ROWS // len(POSES)
    part = np.repeat(np.array(["z_p", "x_p", "y_a"], dtype="<U5"), third)
    part[third - 5:third + 5] = "x_rot"  # a rotation between the first two rests
    order = np.argsort(part == "x_rot", kind="stable")  # the rotation rows last
    lines = ["part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z"]
    lines += [",".join([part[i], str(i), *(str(v) for v in (*acc[i], *gyro[i]))]) for i in order]
    return ("\n".join(lines) + "\n").encode()


def csv(rng) -> bytes:
    """The canonical CSV (the csv format's writer), with temperature and a pose column."""
    import tempfile
    from pathlib import Path

    from accelcal.formats import write_recording

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sample.csv"
        write_recording(path, recording(rng))
        return path.read_bytes()


def imutk(rng) -> bytes:
    acc = specific_force(rng, 415.0) + 32768.0
    out = io.StringIO()
    for t, row in zip(0.02984 + np.arange(ROWS) / RATE_HZ, acc):
        out.write("   " + "   ".join(f"{v:.7e}" for v in (t, *np.round(row))) + "\n")
    return out.getvalue().encode()


def _log_bytes(write) -> bytes:
    """The bytes of a log written by ``write(path)`` into a temporary folder."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        return write(Path(tmp) / "sample").read_bytes()


def _gyro(rng) -> np.ndarray:
    return 0.01 * rng.standard_normal((ROWS, 3))


def ros(rng) -> bytes:
    """A ROS 1 bag (rosbags' writer) with one sensor_msgs/Imu topic, absolute header stamps."""
    from .ros_synthetic import write_imu_bag

    acc, gyro = specific_force(rng), _gyro(rng)
    return _log_bytes(lambda p: write_imu_bag(p.with_suffix(".bag"), 1.7e9 + np.arange(ROWS) / RATE_HZ, acc, gyro,
                                              kind="ros1"))


def px4(rng) -> bytes:
    """A PX4 ULog with the raw sensor_accel and sensor_gyro (timestamps in µs)."""
    from .log_fixtures import write_ulog

    acc, gyro = specific_force(rng), _gyro(rng)
    ts = (10**6 + np.arange(ROWS) * 1e6 / RATE_HZ).astype(np.uint64)
    topics = {(name, 0): {"timestamp": ts + 40, "timestamp_sample": ts, "device_id": np.full(ROWS, k, np.uint32),
                          **{a: v[:, j].astype(np.float32) for j, a in enumerate("xyz")}}
              for k, (name, v) in enumerate((("sensor_accel", acc), ("sensor_gyro", gyro)))}
    return _log_bytes(lambda p: write_ulog(p, topics))


def ardupilot(rng) -> bytes:
    """An ArduPilot DataFlash log of IMU messages."""
    from .log_fixtures import write_dataflash

    acc, gyro = specific_force(rng), _gyro(rng)
    return _log_bytes(lambda p: write_dataflash(p, (10**6 + np.arange(ROWS) * 1e6 / RATE_HZ).astype(np.int64), acc,
                                                gyro))


def _gyro_deg_s(rng) -> np.ndarray:
    """A gyro at rest in deg/s, biased enough that its unit is read from the values (>= 10 deg/s)."""
    return np.array([12.0, -3.0, 5.0]) + 0.2 * rng.standard_normal((ROWS, 3))


def mat(rng) -> bytes:
    """A MATLAB v5 file (SciPy's savemat): a struct of named vectors t_s, ax_mps2..az_mps2,
    gx_dps..gz_dps (units in the names), and a char variable that is not a recording."""
    import scipy.io

    acc, gyro = specific_force(rng), _gyro_deg_s(rng)
    cols = {"t_s": np.arange(ROWS) / RATE_HZ, **{f"a{a}_mps2": acc[:, j] for j, a in enumerate("xyz")},
            **{f"g{a}_dps": gyro[:, j] for j, a in enumerate("xyz")}}
    out = io.BytesIO()
    scipy.io.savemat(out, {"imu": {k: v[:, None] for k, v in cols.items()}, "sensor": "test unit"})
    return out.getvalue()


def rda(rng) -> bytes:
    """An R data file (rdata's writer, gzip): a data frame 't [s]', 'ax [m/s^2]'.., 'gx [deg/s]'.."""
    import tempfile
    from pathlib import Path

    import pandas as pd
    import rdata

    acc, gyro = specific_force(rng), _gyro_deg_s(rng)
    df = pd.DataFrame({"t [s]": np.arange(ROWS) / RATE_HZ, **{f"a{a} [m/s^2]": acc[:, j] for j, a in enumerate("xyz")},
                       **{f"g{a} [deg/s]": gyro[:, j] for j, a in enumerate("xyz")}})
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sample.rda"
        rdata.write_rda(path, {"imu": df})
        return path.read_bytes()


SAMPLES = {"block-log": block_log, "mpu6050": mpu6050, "imucal": imucal, "imucal-annotated": imucal_annotated,
           "csv": csv, "imutk": imutk, "ros": ros, "px4": px4, "ardupilot": ardupilot, "mat": mat, "rda": rda}
