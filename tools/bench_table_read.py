"""The table reader and ``accelcal noise`` on a 10⁶-row CSV against pandas (+ allantools), side by side.

One run, fresh processes interleaved, each measured as CPU time (user + system of the
child, one BLAS thread) and peak resident memory (``ru_maxrss`` of the child)::

    .venv/bin/python tools/bench_table_read.py [--rda PATH] [--repeat 3] [--work DIR]

* reading: ``pandas.read_csv(path)`` against ``accelcal.formats.table.read_table(path)``, each in
  a process that has imported numpy, pandas and accelcal before the clock starts (the read
  alone: CPU time of the call, and the process's peak memory);
* noise: ``accelcal noise FILE.csv --unit g --gyro-unit deg/s --out J`` (the whole command:
  start-up, reading, Allan deviations, the noise fit, its intervals, the JSON) against a
  process running ``pandas.read_csv`` and ``allantools.oadev`` of the six channels at the
  octave τ of tools/bench_noise.py; and the command on the numpy kernels
  (``ACCELCAL_KERNELS=numpy``: no numba start-up, as without the ``fast`` extra).

The file is the ADIS16405 record of ``../shared/data`` (10⁶ × 6: ``Gyro. X/Y/Z`` in deg/s,
``Accel. X/Y/Z`` in g, as the R data file holds them) with a time column ``time`` in s,
written as a user would (pandas ``to_csv``) to ``--work`` (default a temporary folder).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RDA = ROOT / ".." / "shared" / "data" / "smac_adis16405" / "adis_16405_imu1.rda"
ONE_CORE = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

READ = """
import json, resource, sys, time
import numpy as np, pandas as pd
from accelcal.formats.table import read_table
path, which = sys.argv[1], sys.argv[2]
c0 = time.process_time()
if which == "pandas":
    pd.read_csv(path)
else:
    read_table(path)
print(json.dumps({"cpu": time.process_time() - c0, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""
PANDAS_ALLANTOOLS = """
import sys
import allantools
import numpy as np
import pandas as pd
x = pd.read_csv(sys.argv[1]).to_numpy()[:, 1:]
taus = 2.0 ** np.arange(19) / 100.0
out = [allantools.oadev(x[:, j], rate=100.0, data_type="freq", taus=taus) for j in range(x.shape[1])]
"""


def write_csv(rda: Path, out: Path) -> None:
    """The ADIS record as a CSV: ``time`` (s, 100 Hz) and the R matrix's six columns as they are."""
    import pandas as pd

    sys.path.insert(0, str(ROOT / "src"))
    from accelcal_repro.measured.smac import _read_matrix

    _, _, cols, values = _read_matrix(rda, ("Accel. X",))
    df = pd.DataFrame(np.asarray(values, dtype=float), columns=list(cols))
    df.insert(0, "time", np.arange(len(df)) / 100.0)
    df.to_csv(out, index=False)


def child(cmd: list[str], env: dict | None = None) -> tuple[float, float, str]:
    """(CPU seconds, peak RSS [MB], stdout) of one child process (its own rusage: ``os.wait4``)."""
    proc = subprocess.Popen(cmd, env=env or ONE_CORE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise SystemExit(f"{cmd[:4]} failed ({proc.returncode})")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rda", type=Path, default=RDA)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--work", type=Path, default=None)
    args = ap.parse_args(argv)
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        csv = work / "adis.csv"
        if not csv.exists():
            write_csv(args.rda, csv)
        runs = {"read: pandas.read_csv": ("read", [py, "-c", READ, str(csv), "pandas"]),
                "read: accelcal read_table": ("read", [py, "-c", READ, str(csv), "accelcal"]),
                "noise: pandas + allantools oadev": ("proc", [py, "-c", PANDAS_ALLANTOOLS, str(csv)]),
                "noise: accelcal noise": ("proc", [py, "-m", "accelcal.cli", "noise", str(csv), "--unit", "g",
                                                   "--gyro-unit", "deg/s", "--out", str(work / "noise.json")]),
                "noise: accelcal noise, numpy kernels": ("numpy", [py, "-m", "accelcal.cli", "noise", str(csv), "--unit",
                                                                 "g", "--gyro-unit", "deg/s", "--out",
                                                                 str(work / "noise_numpy.json")])}
        res = {k: [] for k in runs}
        for _ in range(args.repeat):
            for label, (kind, cmd) in runs.items():
                cpu, rss, out = child(cmd, {**ONE_CORE, "ACCELCAL_KERNELS": "numpy"} if kind == "numpy" else None)
                if kind == "read":
                    import json

                    d = json.loads(out.strip().splitlines()[-1])
                    cpu, rss = d["cpu"], d["rss_mb"]
                res[label].append((cpu, rss))
    base = {"read": "read: pandas.read_csv", "noise": "noise: pandas + allantools oadev"}
    for label, vals in res.items():
        cpu = float(np.median([v[0] for v in vals]))
        rss = max(v[1] for v in vals)
        ref = float(np.median([v[0] for v in res[base[label.split(":")[0]]]]))
        print(f"{label:<36} CPU median {cpu:6.2f} s (min {min(v[0] for v in vals):.2f}, max {max(v[0] for v in vals):.2f})"
              f"  peak RSS {rss:5.0f} MB   CPU / reference {cpu / ref:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
