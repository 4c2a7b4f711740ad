"""calibrate → JSON → apply on the public recordings, as a user would run it.

``python -m accelcal_repro.measured.roundtrip [DATA_DIR]`` prints:

* the Xsens session (IMU-TK): ``accelcal calibrate`` (g = 9.81744), then ``accelcal apply``
  of that JSON to the same file, and ``|mean of the calibrated samples of each pose| - g``
  per pose with its summary, and how far it is from the fit's own residuals (the JSON
  round trip should lose nothing);
* the three IMU-TK fork sessions of one IMU: the calibration of each applied to every
  session, RMS over the target session's poses of ``|x| - g``, against the raw data.
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from accelcal import cli

DATA = Path(__file__).resolve().parents[4] / "shared" / "data"


def _cli(*args) -> None:
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in args])
    if code != 0:
        raise RuntimeError(err.getvalue().strip())


def pose_magnitudes(cal_json: Path, recording: Path, out_csv: Path, poses_json: Path | None = None) -> np.ndarray:
    """``accelcal apply`` of ``cal_json`` to ``recording``; ``|x| - g`` [m/s²] of each pose of
    ``poses_json`` (default: the calibration's own poses)."""
    _cli("apply", cal_json, recording, "--out", out_csv)
    g = json.loads(cal_json.read_text())["g"]
    poses = json.loads((poses_json or cal_json).read_text())["poses"]
    df = pd.read_csv(out_csv)
    t = df.iloc[:, 0].to_numpy(float)
    x = df[["ax", "ay", "az"]].to_numpy()
    return np.array([np.linalg.norm(x[(t >= a) & (t <= b)].mean(axis=0)) - g
                     for a, b in zip(poses["t_start"], poses["t_end"])])


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    data = Path(argv[0]) if argv else DATA
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        xs = data / "imu_tk_xsens" / "xsens_acc.mat"
        _cli("calibrate", xs, "--g", 9.81744, "--out", tmp / "x.json")
        d = pose_magnitudes(tmp / "x.json", xs, tmp / "x.csv") * 1e3
        res = np.asarray(json.loads((tmp / "x.json").read_text())["residuals"]) * 1e3
        print("Xsens round trip: |calibrated x| - g per pose [mm/s^2]")
        print(" ".join(f"{v:+.3f}" for v in d))
        print(f"n = {len(d)}, mean {d.mean():+.4f}, RMS {np.sqrt(np.mean(d ** 2)):.4f}, median |.| "
              f"{np.median(np.abs(d)):.3f}, max |.| {np.abs(d).max():.3f}; largest difference from the fit's "
              f"residuals {np.abs(d - res).max():.2e}")
        sessions = ("data2", "data3", "data4")
        files = {s: data / "imutk_fork_sessions" / s / "acc_data.txt" for s in sessions}
        for s in sessions:
            _cli("calibrate", files[s], "--out", tmp / f"{s}.json")
        print("\nIMU-TK fork sessions (one IMU): calibration of the row applied to the column's file,")
        print("RMS over the column's poses of |x| - g [mm/s^2]")
        print("        " + "  ".join(f"{s:>6}" for s in sessions))
        for a in sessions:
            row = [np.sqrt(np.mean(pose_magnitudes(tmp / f"{a}.json", files[b], tmp / f"{a}_{b}.csv",
                                                   tmp / f"{b}.json") ** 2)) * 1e3 for b in sessions]
            print(f"{a:>6}  " + "  ".join(f"{v:6.2f}" for v in row))
        raw = [np.sqrt(np.mean((np.linalg.norm(np.asarray(json.loads((tmp / f"{b}.json").read_text())["poses"]["mean"]),
                                               axis=1) - 9.80665) ** 2)) * 1e3 for b in sessions]
        print("   raw  " + "  ".join(f"{v:6.2f}" for v in raw))
    return 0


if __name__ == "__main__":
    sys.exit(main())
