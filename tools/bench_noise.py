"""Time of the noise analysis on the 2.78 h ADIS16405 record (6 channels, 10⁶ samples) against allantools.

Subcommands (each one whole process, for an external timer that runs them in turn)::

    .venv/bin/python tools/bench_noise.py prepare DATA.npy        # the record as (10⁶, 6) float64, SI units
    .venv/bin/python tools/bench_noise.py accelcal DATA.npy OUT.json   # analyse_noise + JSON
    .venv/bin/python tools/bench_noise.py allantools DATA.npy     # allantools.oadev of the 6 channels, same tau
    .venv/bin/python tools/bench_noise.py inprocess DATA.npy      # both in one process, side by side, ratios

``accelcal`` does everything ``accelcal noise`` does after reading the file (Allan
deviations, the five-term fit per axis, the bootstrap intervals, checks, the JSON);
``allantools`` computes only the overlapping Allan deviations (and their error bars) at
the same τ.  Both start from the same ``.npy`` (written by ``prepare`` from the R data
file, outside the repository), so file formats do not enter the comparison.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

FS = 100.0


def prepare(out: str) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from adis_noise import RDA, read_adis

    rec = read_adis(RDA)
    np.save(out, np.hstack([rec.acc, rec.gyro]))


def run_accelcal(data: str, out: str) -> None:
    from accelcal.atomic import write_json_atomic
    from accelcal.noise.report import analyse_noise
    from accelcal.recording import Recording

    x = np.load(data)
    rec = Recording(np.arange(len(x)) / FS, x[:, :3], None, data, unit="m/s^2", gyro=x[:, 3:], gyro_unit="rad/s")
    write_json_atomic(out, analyse_noise(rec).to_dict())


def run_allantools(data: str) -> list:
    import allantools

    x = np.load(data)
    taus = 2.0 ** np.arange(19) / FS
    return [allantools.oadev(x[:, j], rate=FS, data_type="freq", taus=taus) for j in range(x.shape[1])]


def inprocess(data: str, repeat: int = 3) -> None:
    from accelcal.noise.allan import allan_variance
    from accelcal.noise.report import analyse_noise
    from accelcal.recording import Recording

    x = np.load(data)
    rec = Recording(np.arange(len(x)) / FS, x[:, :3], None, data, unit="m/s^2", gyro=x[:, 3:], gyro_unit="rad/s")
    analyse_noise(rec)  # load the compiled kernels once
    times = {"accelcal Allan deviations (6 channels)": [], "accelcal whole analysis": [], "allantools oadev": []}
    for _ in range(repeat):
        for label, f in (("accelcal Allan deviations (6 channels)", lambda: allan_variance(x, FS)),
                         ("accelcal whole analysis", lambda: analyse_noise(rec)),
                         ("allantools oadev", lambda: run_allantools(data))):
            t0 = time.process_time()
            f()
            times[label].append(time.process_time() - t0)
    base = float(np.median(times["allantools oadev"]))
    for label, ts in times.items():
        print(f"{label:<42} CPU median {np.median(ts):6.3f} s (min {min(ts):.3f}, max {max(ts):.3f}); "
              f"/ allantools {np.median(ts) / base:.2f}")
    ours = allan_variance(x, FS)
    ref = run_allantools(data)
    dev = max(float(np.max(np.abs(r[1] / ours.adev[:, j] - 1))) for j, r in enumerate(ref))
    print(f"largest relative difference of the Allan deviations, accelcal vs allantools: {dev:.2g}")


def main(argv) -> int:
    cmd, *rest = argv
    if cmd == "prepare":
        prepare(*rest)
    elif cmd == "accelcal":
        run_accelcal(*rest)
    elif cmd == "allantools":
        run_allantools(*rest)
    elif cmd == "inprocess":
        inprocess(*rest)
    else:
        raise SystemExit(f"unknown subcommand {cmd!r}: prepare, accelcal, allantools or inprocess")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
