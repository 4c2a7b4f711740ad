"""Every `accelcal` command in the README's and docs/' shell blocks runs as printed.

Each page's commands run in order, in-process (``cli.main``), in a temporary folder where the
files they name exist: the real recordings the docs mean (../shared/data) under the docs' own
names, or small sessions simulated for them.  Each command must exit 0, write its ``--out``,
and print its key line (the summary's "written to" line naming that output).  The README's first
calibration is also checked line by line in tests/test_docs.py; here every page's command is run."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli
from accelcal.discrepancy import report
from accelcal.gyro.simulate import random_gyro_matrix, simulate_recording as simulate_gyro_session
from accelcal.simulation import random_directions, simulate_recording
from tests.log_fixtures import write_dataflash, write_ulog
from accelcal.gyro.integrate import log_so3
from accelcal.mag.model import rotvec_to_matrix
from tests.mag_sessions import A_INV, B, DIP, R_TRUE
from tests.ros_synthetic import write_imu_bag
from tests.test_docs import PAGES, _commands

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
G = 9.80665

#: The real recordings the docs name, by the docs' file name (../shared/data/<path>).
REAL = {
    "xsens_acc.mat": "imu_tk_xsens/xsens_acc.mat",
    "xsens_gyro.mat": "imu_tk_xsens/xsens_gyro.mat",
    "acc_data.txt": "imutk_fork_sessions/data4/acc_data.txt",
    "gyro_data.txt": "imutk_fork_sessions/data4/gyro_data.txt",
    "imu.txt": "snu_static3/imu_good2.txt",  # good1: 9 rests found, full-lls needs 10 (refused in one line)
    "measured_angular_rates.mat": "ctu_ferraris/measured_angular_rates.mat",
    "adis_16405_imu1.rda": "smac_adis16405/adis_16405_imu1.rda",
    "mpu.csv": "mpu6050_suarez/example_data_calibration.csv",
    "rosbag2_2023_08_11-21_37_35": "imutk_fork_sessions/data1/rosbag2_2023_08_11-21_37_35",
}


def _acc_session(seed=3, poses=24):
    rng = np.random.default_rng(seed)
    return simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, poses - 1)]), G, np.eye(3),
                              np.array([0.02, -0.01, 0.03]), noise_std=0.01, init_rest_s=10.0, rest_s=2.0,
                              move_s=1.0)


def _csv(path, columns: dict, fmt="%.7g"):
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=",", header=",".join(columns),
               comments="", fmt=fmt)


def _session_csv(path):
    s = _acc_session()
    _csv(path, {"t": s["t"], "ax": s["acc"][:, 0], "ay": s["acc"][:, 1], "az": s["acc"][:, 2]})


def _log_csv(path):  # a logger's own names, in g, time in µs
    s = _acc_session(4)
    _csv(path, {"stamp": np.round(s["t"] * 1e6), **{f"ch{k}": s["acc"][:, k] / G for k in range(3)}})


def _log_txt(path):  # no time column: 400 Hz from --rate
    s = _acc_session(5)
    np.savetxt(path, s["acc"], fmt="%.6f")


def _rests_csv(path):  # the known rests of session.csv (start,end in s)
    s = _acc_session()
    moving = np.r_[False, np.linalg.norm(np.diff(s["acc"], axis=0), axis=1) > 0.2]
    edges = np.flatnonzero(np.diff(moving.astype(int)))
    starts, ends = np.r_[0, edges[1::2] + 1], np.r_[edges[::2], len(moving) - 1]
    rows = [(s["t"][a] + 0.2, s["t"][b] - 0.2) for a, b in zip(starts, ends) if s["t"][b] - s["t"][a] > 1.0]
    np.savetxt(path, rows, delimiter=",", header="start,end", comments="", fmt="%.3f")


def _static(n=30_000, seed=1):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 100.0
    return t, [0, 0, G] + 0.01 * rng.standard_normal((n, 3)), 0.001 * rng.standard_normal((n, 3))


def _static_csv(path):
    t, acc, _ = _static()
    _csv(path, {"t": t, "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2]}, fmt="%.6f")


def _static_bag(path):
    t, acc, gyro = _static()
    write_imu_bag(path, 1.7e9 + t, acc, gyro, kind="ros1", topic="/imu/data", serialize="fast")


def _gyro_session():
    rng = np.random.default_rng(24)
    return simulate_gyro_session(rng, C=random_gyro_matrix(rng), gyro_bias=[0.01, -0.02, 0.005],
                                 M=np.diag([1.01, 0.99, 1.0]), acc_bias=[0.1, -0.05, 0.2], n_motions=20)


def _imu_mag_session(seed=0, rests=14):
    """(t, acc [m/s²], gyro [rad/s], mag [µT]) of one motion: tests/mag_sessions.py's session (rests of 2 s,
    turns of 0.6 s, its hard and soft iron) with the gyro's rates of the same turns."""
    rng = np.random.default_rng(seed)
    dip = np.radians(DIP)
    field = np.array([0, np.cos(dip), -np.sin(dip)])
    Q, qs = np.eye(3), []
    for _ in range(rests):
        Qn = rotvec_to_matrix(rng.normal(size=3) * 1.5) @ Q
        qs += [rotvec_to_matrix(s * log_so3(Qn @ Q.T)) @ Q for s in np.linspace(0, 1, 60)] + [Qn] * 200
        Q = Qn
    qs = np.array(qs)
    acc = qs @ [0, 0, G] + rng.normal(size=(len(qs), 3)) * 0.01
    gyro = np.vstack([[0, 0, 0], [-log_so3(b @ a.T) * 100.0 for a, b in zip(qs[:-1], qs[1:])]])
    mag = B + (np.einsum("ij,njk,k->ni", R_TRUE.T, qs, field)) @ A_INV.T + rng.normal(size=(len(qs), 3)) * 0.1
    return np.arange(len(qs)) / 100.0, acc, gyro + rng.normal(size=gyro.shape) * 1e-3, mag


def _session_bag(path):  # an IMU session and a magnetometer beside it (ROS 1)
    t, acc, gyro, m = _imu_mag_session()
    mag = {"/imu/mag": (1.7e9 + t, m * 1e-6, 0.001)}
    write_imu_bag(path, 1.7e9 + t, acc, gyro, kind="ros1", topic="/imu/data", serialize="fast", mag=mag)


def _flight_ulg(path):  # PX4: the raw sensor_accel and sensor_gyro, and two compasses
    t, acc, gyro, m = _imu_mag_session()
    us = (1e6 * t).astype(np.uint64) + 1_000_000
    topics = {(name, 0): {"timestamp": us + 40, "timestamp_sample": us, "device_id": np.full(len(t), k, np.uint32),
                          **{a: v[:, j].astype(np.float32) for j, a in enumerate("xyz")}}
              for k, (name, v) in enumerate((("sensor_accel", acc), ("sensor_gyro", gyro)))}
    for inst in (0, 1):  # gauss
        topics[("sensor_mag", inst)] = {"timestamp": us, **{a: (m[:, j] / 100).astype(np.float32)
                                                            for j, a in enumerate("xyz")}}
    write_ulog(path, topics)


def _session_bin(path):  # ArduPilot: IMU and MAG
    t, acc, gyro, m = _imu_mag_session()
    us = (1e6 * t).astype(np.int64) + 1_000_000
    mag = [(u, 0, *np.trunc(10 * mm), 0, 0, 0, 0, 0, 0, 1, u) for u, mm in zip(us[::5], m[::5])]  # milligauss
    identity = {"COMPASS_SCALE": 1.0, **{f"COMPASS_DIA_{a}": 1.0 for a in "XYZ"},  # ArduPilot's correction: none
                **{f"COMPASS_ODI_{a}": 0.0 for a in "XYZ"}}
    write_dataflash(path, us, acc, gyro, mag=mag, params=identity)


def _sections_session(path):  # imucal's Ferraris session and its section list (gyroscope.md)
    shutil.copy(DATA / "imucal_ferraris" / "example_ferraris_session.csv", path.parent / "session.csv")
    shutil.copy(DATA / "imucal_ferraris" / "example_ferraris_session_list.json", path.parent / "sections.json")


def _mag_session_csv(path):  # accelerometer and magnetometer columns
    t, acc, _, m = _imu_mag_session()
    _csv(path, {"t": t, "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2],
                "mx_uT": m[:, 0], "my_uT": m[:, 1], "mz_uT": m[:, 2]})


def _mag_only_csv(path):  # a magnetometer alone, in µT (a file of counts is refused for autopilot exports)
    _, _, _, m = _imu_mag_session()
    _csv(path, {"mx_uT": m[:, 0], "my_uT": m[:, 1], "mz_uT": m[:, 2]})


def _noise_json(path):  # a noise report of both sensors, which the export commands read
    t, acc, gyro = _static()
    _csv(path.with_suffix(".csv"), {"t": t, **{f"a{x}": acc[:, k] for k, x in enumerate("xyz")},
                                    **{f"g{x}": gyro[:, k] for k, x in enumerate("xyz")}}, fmt="%.6f")
    assert cli.main(["noise", str(path.with_suffix(".csv")), "--gyro-unit", "rad/s", "--out", str(path)]) == 0


#: Simulated inputs by the docs' file name; a page may mean another file under a name (PAGE_FILES).
MAKERS = {
    "session.csv": _session_csv, "flight.csv": _session_csv, "log.csv": _log_csv, "log.txt": _log_txt,
    "rests.csv": _rests_csv, "static.csv": _static_csv, "static.bag": _static_bag,
    "static_2h.bag": _static_bag, "session.bag": _session_bag, "flight.ulg": _flight_ulg,
    "session.bin": _session_bin, "noise.json": _noise_json, "mag_only.csv": _mag_only_csv,
}
PAGE_FILES = {
    "gyroscope.md": {"session.csv": _sections_session, "sections.json": _sections_session},
    "magnetometer.md": {"session.csv": _mag_session_csv},
}


def _inputs(command: str) -> list[str]:
    """The file names a command reads (positional arguments and the options that take a file)."""
    args = shlex.split(command)[1:]
    out = [a for i, a in enumerate(args[1:], 1) if not a.startswith("-") and not args[i - 1].startswith("--")]
    return out + [args[i + 1] for i, a in enumerate(args[:-1]) if a in ("--gyro", "--intervals", "--noise")]


def _make(folder: Path, name: str, page: str) -> None:
    if (folder / name).exists():
        return
    if name in REAL:
        if not (DATA / REAL[name]).exists():
            pytest.skip(f"{REAL[name]} not in ../shared/data")
        (folder / name).symlink_to(DATA / REAL[name])
        return
    make = PAGE_FILES.get(page, {}).get(name) or MAKERS.get(name)
    assert make is not None, f"{page}: no input made for {name!r}: add it to MAKERS or REAL"
    if make is _sections_session and not DATA.exists():
        pytest.skip("imucal's session not in ../shared/data")
    make(folder / name)


#: The README's commands (and docs/index.md, its copy) run in tests/test_docs.py.
@pytest.mark.parametrize("page", [p for p in PAGES if _commands(p.read_text()) and p.name not in ("README.md", "index.md")],
                         ids=lambda p: p.name)
def test_every_documented_command_runs(page, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    # the discrepancy command's noise bootstrap at a test's size (its defaults: tests/test_discrepancy_cli.py)
    monkeypatch.setattr(report, "DEFAULT_STOCHASTIC", report.StochasticSettings(n_boot=19, n_resim=1))
    written = set()
    for command in _commands(page.read_text()):
        for name in _inputs(command):
            if name not in written:
                _make(tmp_path, name, page.name)
        args = shlex.split(command)[1:]
        code = cli.main(args)
        err = capsys.readouterr().err
        assert code == 0, f"{page.name}: `{command}` exits {code}:\n{err[-1500:]}"
        out = args[args.index("--out") + 1]
        assert any(Path(out).parent.glob(Path(out).name + "*")), f"{page.name}: `{command}` wrote no {out}"
        assert out in err, f"{page.name}: `{command}` does not name {out}:\n{err[-1500:]}"
        written.add(out)


def test_the_input_finder_sees_positional_files_and_file_options():
    assert _inputs("accelcal calibrate a.csv --gyro b.txt --g 9.81 --out c.json") == ["a.csv", "b.txt"]
    assert _inputs("accelcal export cal.json --noise n.json --to px4 --out x") == ["cal.json", "n.json"]


def test_every_input_made_is_one_the_docs_name():
    """No maker outlives the command that needed it (the docs' own names, page by page)."""
    named = {name for page in PAGES for c in _commands(page.read_text()) for name in _inputs(c)}
    assert set(MAKERS) | set(REAL) <= named | {"sections.json"}, sorted(set(MAKERS) | set(REAL) - named)
