"""Build and run the gyro calibration peers (IMU-TK, imucal) and record their outputs.

    .venv/bin/python tools/gyro_peers.py build-imutk [--peers /work/peers]
    .venv/bin/python tools/gyro_peers.py run-imutk   [--peers /work/peers] [--out results/gyro/peers]
    .venv/bin/python tools/gyro_peers.py run-imucal  [--out results/gyro/peers]

IMU-TK (Tedaldi, Pretto, Menegatti, ICRA 2014; github.com/Kyle-ak/imu_tk, commit
7780270fb9a227c79323199303f23989e689a89d) is fetched and built outside this repository
(``--peers``, default /work/peers); none of its code is committed here.  Its CMake build
needs Qt4, OpenGL and GLUT for the visualisation, which the calibration does not use: this
tool compiles the calibration sources (``src/calibration.cpp``, ``filters.cpp``,
``io_utils.cpp``) with a no-op stand-in for the plotting (``Plot``, ``waitForKey``: the
example app calls them in verbose mode and would wait for a key press), against Ceres and
Eigen from Debian (``apt-get install libceres-dev libeigen3-dev libboost-dev``).  One
local fix is applied to the peer's copy: three setters of ``calibration.h`` are declared
to return a value and do not (undefined behaviour that GCC -O2 may turn into a crash);
they get the ``return``.

Runs:

* ``test_imu_calib`` (IMU-TK's own example app, unchanged) on the Xsens files
  ``../shared/data/imu_tk_xsens/``: its ``.calib`` results and its run time (median of
  ``--runs`` whole-process runs);
* ``imutk_calib`` (a 40-line driver in this file, compiled beside it: the example app's
  calls with the settings as arguments) on the IMU-TK fork sessions data1-4 and the SNU
  sessions, for which the example's Xsens settings (raw counts, 50 s initial rest) do not
  apply;
* imucal's ``FerrarisCalibration`` on its own example session (``run-imucal``; the workflow's
  gyro stage runs it itself).

The workflow cannot build IMU-TK (no downloads or builds at run time): its gyro stage reads
``imutk.json`` when the config's ``gyro.imutk_run`` names it.

Everything is written as JSON into ``--out`` with the command, the settings, the peer's
version and the wall time, so that the comparison can be rerun.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
IMUTK_COMMIT = "7780270fb9a227c79323199303f23989e689a89d"

PLOT_STUB = r"""
// No-op stand-in for IMU-TK's gnuplot/Qt visualisation (written by accelcal's tools/gyro_peers.py).
#include "imu_tk/visualization.h"
namespace imu_tk {
class Plot::PlotImpl {};
Plot::Plot() {}
template <typename _T> void Plot::plotSamples(const std::vector< TriadData_<_T> > &, DataInterval) {}
template <typename _T> void Plot::plotIntervals(const std::vector< TriadData_<_T> > &,
                                                const std::vector< DataInterval > &, DataInterval) {}
template void Plot::plotSamples<double>(const std::vector< TriadData_<double> > &, DataInterval);
template void Plot::plotIntervals<double>(const std::vector< TriadData_<double> > &,
                                          const std::vector< DataInterval > &, DataInterval);
template void Plot::plotSamples<float>(const std::vector< TriadData_<float> > &, DataInterval);
template void Plot::plotIntervals<float>(const std::vector< TriadData_<float> > &,
                                         const std::vector< DataInterval > &, DataInterval);
void waitForKey() {}
}
"""

DRIVER = r"""
// IMU-TK's example calls with the settings as arguments (written by accelcal's tools/gyro_peers.py).
// usage: imutk_calib ACC GYRO G INIT_S ACC_BIAS0 GYRO_SCALE0 N_SAMPLES OUT_PREFIX
#include <cstdlib>
#include <iostream>
#include <string>
#include "imu_tk/io_utils.h"
#include "imu_tk/calibration.h"
using namespace imu_tk;
using namespace Eigen;
int main(int argc, char **argv) {
  if (argc < 9) {
    std::cerr << "usage: imutk_calib ACC GYRO G INIT_S ACC_BIAS0 GYRO_SCALE0 N_SAMPLES OUT" << std::endl;
    return 2;
  }
  std::vector< TriadData > acc, gyro;
  importAsciiData(argv[1], acc, imu_tk::TIMESTAMP_UNIT_SEC);
  importAsciiData(argv[2], gyro, imu_tk::TIMESTAMP_UNIT_SEC);
  CalibratedTriad init_acc, init_gyro;
  double b0 = std::atof(argv[5]), s0 = std::atof(argv[6]);
  init_acc.setBias(Vector3d(b0, b0, b0));
  init_gyro.setScale(Vector3d(s0, s0, s0));
  MultiPosCalibration mp;
  mp.setInitStaticIntervalDuration(std::atof(argv[4]));
  mp.setIntarvalsNumSamples(std::atoi(argv[7]));
  mp.setInitAccCalibration(init_acc);
  mp.setInitGyroCalibration(init_gyro);
  mp.setGravityMagnitude(std::atof(argv[3]));
  mp.enableVerboseOutput(true);
  mp.enableAccUseMeans(false);
  bool ok = mp.calibrateAccGyro(acc, gyro);
  std::string out(argv[8]);
  mp.getAccCalib().save(out + "_acc.calib");
  mp.getGyroCalib().save(out + "_gyro.calib");
  return ok ? 0 : 1;
}
"""

#: Setters of calibration.h declared non-void without a return statement (peer bug).
_SETTER_FIXES = (
    ("{ init_interval_duration_ = duration; };", "{ init_interval_duration_ = duration; return duration; };"),
    ("{ interval_n_samples_ = num; };", "{ interval_n_samples_ = num; return num; };"),
    ("{ optimize_gyro_bias_ = enabled; };", "{ optimize_gyro_bias_ = enabled; return enabled; };"),
)


def _imutk_dir(peers: Path) -> Path:
    return peers / "imu_tk"


def build_imutk(peers: Path) -> Path:
    """Compile IMU-TK's calibration and the two apps into ``peers/imu_tk/build_accelcal``."""
    src = _imutk_dir(peers)
    if not (src / "src" / "calibration.cpp").exists():
        raise SystemExit(f"{src}: no IMU-TK checkout (git clone https://github.com/Kyle-ak/imu_tk, "
                         f"commit {IMUTK_COMMIT})")
    header = src / "include" / "imu_tk" / "calibration.h"
    text = header.read_text()
    for old, new in _SETTER_FIXES:
        text = text.replace(old, new)
    header.write_text(text)
    build = src / "build_accelcal"
    build.mkdir(exist_ok=True)
    (build / "plot_stub.cpp").write_text(PLOT_STUB)
    (build / "imutk_calib.cpp").write_text(DRIVER)
    flags = ["-O2", "-std=c++17", "-I", str(src / "include"), "-I", "/usr/include/eigen3", "-DNDEBUG"]
    objs = []
    for cpp in (src / "src" / "calibration.cpp", src / "src" / "filters.cpp", src / "src" / "io_utils.cpp",
                build / "plot_stub.cpp"):
        obj = build / (cpp.stem + ".o")
        subprocess.run(["g++", *flags, "-c", str(cpp), "-o", str(obj)], check=True)
        objs.append(str(obj))
    libs = ["-lceres", "-lglog", "-lgflags", "-lpthread"]
    apps = (("test_imu_calib", src / "apps" / "test_imu_calib.cpp"), ("imutk_calib", build / "imutk_calib.cpp"))
    for app, cpp in apps:
        subprocess.run(["g++", *flags, str(cpp), *objs, "-o", str(build / app), *libs], check=True)
    return build


def _read_calib(path: Path) -> dict:
    """IMU-TK's ``.calib``: T (3x3), blank, K (3x3), blank, b (3)."""
    rows = [[float(v) for v in line.split()] for line in path.read_text().splitlines() if line.strip()]
    return {"T": rows[0:3], "K": rows[3:6], "b": [r[0] for r in rows[6:9]]}


def _choice_lines(stdout: str) -> list[str]:
    """IMU-TK's verbose lines on the threshold multipliers it tried and the one it kept."""
    keys = ("intervals using threshold multiplier", "Better calibration obtained", "Can't obtain")
    return [line.strip() for line in stdout.splitlines() if any(k in line for k in keys)]


def _timed(cmd: list[str], cwd: Path, runs: int) -> tuple[subprocess.CompletedProcess, list[float]]:
    times, proc = [], None
    for _ in range(max(1, runs)):
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
        times.append(time.perf_counter() - t0)
    return proc, times


#: Settings of the driver per session: files, g, initial rest [s], initial acc bias, initial gyro scale,
#: samples per interval (IMU-TK's default 100).  The fork's app rests 5 s at the start; the SNU
#: sessions start with 7-9 s at rest.
SESSIONS = {
    **{f"fork_{s}": (DATA / "imutk_fork_sessions" / s / "acc_data.txt",
                     DATA / "imutk_fork_sessions" / s / "gyro_data.txt", 9.81, 5.0, 0.0, 1.0, 100)
       for s in ("data1", "data2", "data3", "data4")},
    **{f"snu_{s}": (DATA / "snu_static3" / f"imu_{s}.txt", None, 9.79871, 7.0, 0.0, 1.0, 100)
       for s in ("good1", "good2", "good3")},
}


def _imutk_ascii(path: Path, work: Path, name: str) -> tuple[Path, Path]:
    """The SNU log (``# time tx ty tz wx wy wz ...``) as IMU-TK's two ASCII files (t x y z)."""
    import numpy as np

    header = path.read_text().splitlines()[0].lstrip("#").split()
    x = np.loadtxt(path, comments="#")
    c = {k: i for i, k in enumerate(header)}
    t = x[:, c["time"]] - x[0, c["time"]]
    out = []
    for kind, cols in (("acc", ("tx", "ty", "tz")), ("gyro", ("wx", "wy", "wz"))):
        f = work / f"{name}_{kind}.txt"
        np.savetxt(f, np.column_stack([t] + [x[:, c[k]] for k in cols]), fmt="%.9f")
        out.append(f)
    return out[0], out[1]


def run_imutk(peers: Path, out: Path, runs: int) -> None:
    build = _imutk_dir(peers) / "build_accelcal"
    if not (build / "test_imu_calib").exists():
        build = build_imutk(peers)
    out.mkdir(parents=True, exist_ok=True)
    records = {}
    work = out / "imutk_work"
    work.mkdir(exist_ok=True)
    xs = DATA / "imu_tk_xsens"
    proc, times = _timed([str(build / "test_imu_calib"), str(xs / "xsens_acc.mat"), str(xs / "xsens_gyro.mat")],
                         work, runs)
    records["xsens"] = {"command": "test_imu_calib xsens_acc.mat xsens_gyro.mat", "returncode": proc.returncode,
                        "wall_s": times, "acc": _read_calib(work / "test_imu_acc.calib"),
                        "gyro": _read_calib(work / "test_imu_gyro.calib"), "choice": _choice_lines(proc.stdout),
                        "stdout_tail": proc.stdout[-3000:]}
    for name, (acc, gyro, g, init, b0, s0, nsamp) in SESSIONS.items():
        prefix = work / name
        if gyro is None:
            acc, gyro = _imutk_ascii(acc, work, name)
        cmd = [str(build / "imutk_calib"), str(acc), str(gyro), str(g), str(init), str(b0), str(s0), str(nsamp),
               str(prefix)]
        proc, times = _timed(cmd, work, 1)
        rec = {"command": " ".join(["imutk_calib", *cmd[1:]]), "returncode": proc.returncode, "wall_s": times,
               "settings": {"g": g, "init_s": init, "acc_bias0": b0, "gyro_scale0": s0, "interval_samples": nsamp},
               "choice": _choice_lines(proc.stdout), "stdout_tail": proc.stdout[-3000:]}
        if proc.returncode == 0:
            rec["acc"] = _read_calib(Path(f"{prefix}_acc.calib"))
            rec["gyro"] = _read_calib(Path(f"{prefix}_gyro.calib"))
        records[name] = rec
    meta = {"peer": "IMU-TK", "repository": "github.com/Kyle-ak/imu_tk", "commit": IMUTK_COMMIT,
            "compiler": subprocess.run(["g++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]}
    (out / "imutk.json").write_text(json.dumps({"meta": meta, "runs": records}, indent=1))
    shutil.rmtree(work / "__pycache__", ignore_errors=True)
    print(f"wrote {out / 'imutk.json'}")


def run_imucal(out: Path) -> None:
    """imucal's Ferraris calibration of its example session (its own example's settings,
    accelcal_repro.gyro.ferraris_sessions.run_imucal: the workflow's gyro stage runs the same)."""
    from accelcal_repro.gyro.ferraris_sessions import run_imucal as imucal_of

    d = DATA / "imucal_ferraris"
    cal = imucal_of(d / "example_ferraris_session.csv", d / "example_ferraris_session_list.json")
    meta = cal.pop("meta")
    out.mkdir(parents=True, exist_ok=True)
    (out / "imucal.json").write_text(json.dumps({"meta": {**meta, "expected_angle": -360.0}, "calibration": cal},
                                                indent=1))
    print(f"wrote {out / 'imucal.json'}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=("build-imutk", "run-imutk", "run-imucal"))
    ap.add_argument("--peers", type=Path, default=Path("/work/peers"))
    ap.add_argument("--out", type=Path, default=REPO / "results" / "gyro" / "peers")
    ap.add_argument("--runs", type=int, default=5, help="timed runs of test_imu_calib (default 5)")
    a = ap.parse_args(argv)
    if a.what == "build-imutk":
        print(build_imutk(a.peers))
    elif a.what == "run-imutk":
        run_imutk(a.peers, a.out, a.runs)
    else:
        run_imucal(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
