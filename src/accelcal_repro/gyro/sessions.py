"""The real sessions with gyro data: reading them, calibrating accelerometer and gyro together.

Readers for the gyro columns arrive with the format registry; until then each session is
read here, as its data README describes it (``../shared/data/README.md``):

==============  ==========================================  =========  ========  ==========
session         files                                       acc        gyro      g [m/s²]
==============  ==========================================  =========  ========  ==========
``xsens``       imu_tk_xsens/xsens_{acc,gyro}.mat           counts     counts    9.81744
``fork_dataK``  imutk_fork_sessions/dataK/{acc,gyro}_data   m/s²       rad/s     9.81
``snu_goodK``   snu_static3/imu_goodK.txt (``# time tx ..``)  m/s²       rad/s     9.79871
==============  ==========================================  =========  ========  ==========

(g of the fork sessions is not recorded; 9.81 is what the fork's configuration uses.)

:func:`calibrate_session` finds the rests (:func:`accelcal.static_auto.choose_static`: the
default settings unless they find too few poses, then the candidates), fits the
accelerometer (full LLS) and the gyro (:func:`accelcal.gyro.calibrate.calibrate_gyro`),
and times both.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[4] / "shared" / "data"

SESSIONS = ("xsens", "fork_data1", "fork_data2", "fork_data3", "fork_data4", "snu_good1", "snu_good2", "snu_good3")


@dataclass(frozen=True)
class Session:
    name: str
    t: np.ndarray
    acc: np.ndarray
    gyro: np.ndarray
    t_gyro: np.ndarray
    acc_unit: str
    gyro_unit: str
    g: float
    source: str


def load(name: str, data: Path = DATA) -> Session:
    """One session of :data:`SESSIONS`."""
    if name == "xsens":
        a = np.loadtxt(data / "imu_tk_xsens" / "xsens_acc.mat")
        g = np.loadtxt(data / "imu_tk_xsens" / "xsens_gyro.mat")
        return Session(name, a[:, 0], a[:, 1:4], g[:, 1:4], g[:, 0], "counts", "counts", 9.81744, "imu_tk_xsens")
    if name.startswith("fork_"):
        d = data / "imutk_fork_sessions" / name[5:]
        a, g = np.loadtxt(d / "acc_data.txt"), np.loadtxt(d / "gyro_data.txt")
        return Session(name, a[:, 0], a[:, 1:4], g[:, 1:4], g[:, 0], "m/s^2", "rad/s", 9.81, str(d))
    if name.startswith("snu_"):
        path = data / "snu_static3" / f"imu_{name[4:]}.txt"
        header = path.read_text().splitlines()[0].lstrip("#").split()
        x = np.loadtxt(path, comments="#")
        col = {c: i for i, c in enumerate(header)}
        acc = x[:, [col["tx"], col["ty"], col["tz"]]]
        gyro = x[:, [col["wx"], col["wy"], col["wz"]]]
        return Session(name, x[:, col["time"]] - x[0, col["time"]], acc, gyro, x[:, col["time"]] - x[0, col["time"]],
                       "m/s^2", "rad/s", 9.79871, str(path))
    raise KeyError(f"unknown session {name!r}; known: {', '.join(SESSIONS)}")


def calibrate_session(s: Session, *, estimator: str = "gyro_iterative", integrator: str = "magnus4",
                      bias: str = "interpolated", g_sensitivity="auto", static: str = "auto") -> dict:
    """Accelerometer and gyro of one session; ``static``: 'auto' (defaults, candidates if
    they find too few poses), 'search' (always the candidates), 'default'."""
    from accelcal.calibration import calibrate_poses
    from accelcal.gyro.calibrate import calibrate_gyro
    from accelcal.static import detect_static
    from accelcal.static_auto import choose_static

    t0 = time.perf_counter()
    note = "default detection settings"
    if static == "search":
        choice = choose_static(s.t, s.acc, s.g, unit=s.acc_unit)
        poses, note = choice.poses, choice.describe()
    else:
        try:
            poses = detect_static(s.t, s.acc)
            enough = len(poses) >= 12
        except Exception:  # noqa: BLE001 - any failure of the defaults sends us to the candidates
            enough = False
        if not enough:
            if static == "default":
                raise
            choice = choose_static(s.t, s.acc, s.g, unit=s.acc_unit)
            poses, note = choice.poses, choice.describe()
    acc_cal = calibrate_poses(poses, s.g, "full_lls", unit=s.acc_unit)
    t1 = time.perf_counter()
    gcal = calibrate_gyro(s.t, s.gyro, poses, acc_cal, raw_unit=s.gyro_unit, t_gyro=s.t_gyro, estimator=estimator,
                          integrator=integrator, bias=bias, acc=s.acc, g_sensitivity=g_sensitivity)
    t2 = time.perf_counter()
    return {"session": s.name, "poses": poses, "acc": acc_cal, "gyro": gcal, "static_note": note,
            "acc_seconds": t1 - t0, "gyro_seconds": t2 - t1}


__all__ = ["DATA", "SESSIONS", "Session", "calibrate_session", "load"]
