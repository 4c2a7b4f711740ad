"""Time of the noise analysis on the 2.78 h ADIS16405 record (6 channels, 10⁶ samples) against allantools.

One run, side by side, each measured as CPU time of one core (``OMP/OPENBLAS`` threads 1)::

    .venv/bin/python tools/bench_noise.py [--rda PATH] [--repeat 5] [--work DIR]

* in process, after a warm-up: accelcal's Allan deviations of the six channels
  (:func:`accelcal.noise.allan_variance`), the whole analysis
  (:func:`accelcal.noise.analyse_noise`: Allan deviations, the five-term fit per axis, the
  bootstrap intervals, the checks) and ``allantools.oadev`` of the six channels at the same
  τ, interleaved, medians and ratios;
* whole processes, the medians of ``--repeat`` runs each, interleaved: the analysis
  and its JSON on the record as a ``.npy`` (what ``accelcal noise`` does once the file is
  read: the same work as the allantools process, file formats aside), a process
  computing ``allantools.oadev`` of the six channels from the same ``.npy``, and
  ``accelcal noise`` itself on the record written as a ROS 2 bag (sqlite3, one
  ``sensor_msgs/Imu`` message per sample: reading 10⁶ messages included).

The record is read once from the R data file (``rdata``, the ``workflow`` extra) and written
to ``--work`` (default a temporary folder), outside the repository.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RDA = ROOT / ".." / "shared" / "data" / "smac_adis16405" / "adis_16405_imu1.rda"
FS = 100.0
ONE_CORE = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

ACCELCAL_NPY = """
import sys
import numpy as np
from accelcal.atomic import write_json_atomic
from accelcal.noise import analyse_noise
from accelcal.recording import Recording
x = np.load(sys.argv[1])
rec = Recording(np.arange(len(x)) / 100.0, x[:, :3], None, sys.argv[1], unit="m/s^2", gyro=x[:, 3:], gyro_unit="rad/s")
write_json_atomic(sys.argv[2], analyse_noise(rec).to_dict())
"""
ALLANTOOLS_NPY = """
import sys
import numpy as np
import allantools
x = np.load(sys.argv[1])
taus = 2.0 ** np.arange(19) / 100.0
out = [allantools.oadev(x[:, j], rate=100.0, data_type="freq", taus=taus) for j in range(x.shape[1])]
"""


def allantools_oadev(x):
    import allantools

    taus = 2.0 ** np.arange(19) / FS
    return [allantools.oadev(x[:, j], rate=FS, data_type="freq", taus=taus) for j in range(x.shape[1])]


def prepare(rda: Path, work: Path):
    """The record as ``.npy`` (10⁶ × 6, SI units) and as a ROS 2 bag (header stamps from 1.7e9 s)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' bag writer
    from tests.ros_synthetic import write_imu_bag
    from accelcal_repro.measured.smac import read_smac_imu

    rec = read_smac_imu(rda)
    x = np.hstack([rec.acc, rec.gyro])
    np.save(work / "adis.npy", x)
    write_imu_bag(work / "adis_bag", 1.7e9 + rec.t, rec.acc, rec.gyro, kind="ros2-sqlite3", serialize="fast")
    return x


def in_process(x, repeat: int) -> None:
    from accelcal.noise import allan_variance, analyse_noise
    from accelcal.recording import Recording

    rec = Recording(np.arange(len(x)) / FS, x[:, :3], None, "adis", unit="m/s^2", gyro=x[:, 3:], gyro_unit="rad/s")
    analyse_noise(rec)  # the compiled kernels loaded once
    allantools_oadev(x[:1000])
    runs = {"accelcal Allan deviations (6 channels)": lambda: allan_variance(x, FS),
            "accelcal whole analysis": lambda: analyse_noise(rec),
            "allantools oadev (6 channels)": lambda: allantools_oadev(x)}
    times = {k: [] for k in runs}
    for _ in range(repeat):
        for label, f in runs.items():
            t0 = time.process_time()
            f()
            times[label].append(time.process_time() - t0)
    _print("in process", times, "allantools oadev (6 channels)")
    ours = allan_variance(x, FS)
    dev = max(float(np.max(np.abs(r[1] / ours.adev[:, j] - 1))) for j, r in enumerate(allantools_oadev(x)))
    print(f"  largest relative difference of the Allan deviations, accelcal vs allantools: {dev:.2g}")


def processes(work: Path, repeat: int) -> None:
    py = sys.executable
    runs = {"accelcal analysis + JSON (.npy)": [py, "-c", ACCELCAL_NPY, str(work / "adis.npy"),
                                                str(work / "out_npy.json")],
            "allantools oadev (.npy)": [py, "-c", ALLANTOOLS_NPY, str(work / "adis.npy")],
            "accelcal noise on a ROS 2 bag (reading it)": [py, "-m", "accelcal.cli", "noise", str(work / "adis_bag"),
                                                           "--out", str(work / "out_bag.json")]}
    times = {k: [] for k in runs}
    for _ in range(repeat):
        for label, cmd in runs.items():
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            subprocess.run(cmd, check=True, env=ONE_CORE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            times[label].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    _print("whole processes (user + system CPU)", times, "allantools oadev (.npy)")


def _print(title: str, times: dict, base_label: str) -> None:
    base = float(np.median(times[base_label]))
    print(f"{title}:")
    for label, ts in times.items():
        print(f"  {label:<40} CPU median {np.median(ts):6.3f} s (min {min(ts):.3f}, max {max(ts):.3f}); "
              f"/ allantools {np.median(ts) / base:.2f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rda", type=Path, default=RDA)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--work", type=Path, default=None)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        x = prepare(args.rda, work)
        in_process(x, args.repeat)
        processes(work, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
