"""The real sessions with gyro data: read and calibrated as ``accelcal calibrate`` does.

===================  ==========================================  ======  ======  ==========  =================
session              files (``../shared/data``)                  acc     gyro    g [m/s²]    protocol
===================  ==========================================  ======  ======  ==========  =================
``xsens``            imu_tk_xsens/xsens_{acc,gyro}.mat           counts  counts  9.81744     multi-position
``fork_dataK``       imutk_fork_sessions/dataK/{acc,gyro}_data   m/s²    rad/s   9.81        multi-position
``snu_goodK``        snu_static3/imu_goodK.txt (``# time tx ..``)  m/s²    rad/s   9.79871     multi-position
``mpu6050``          mpu6050_suarez/example_data_calibration     counts  counts  9.80665     multi-position
``imucal_ferraris``  imucal_ferraris/example_ferraris_session    m/s²    deg/s   9.81        Ferraris
``imucal_annotated``  imucal_ferraris/annotated_session           counts  counts  9.81        Ferraris
===================  ==========================================  ======  ======  ==========  =================

(g of the fork sessions is not recorded; 9.81 is what the fork's configuration uses.  The
SNU header names the specific force ``tx, ty, tz``, which say nothing of acceleration:
``--columns ax=tx,ay=ty,az=tz``.  The imucal example is read at its 102.4 Hz and
calibrated from its section list; its six holds allow only a bias-only accelerometer.)

:func:`calibrate_session` reads a session with :func:`accelcal.formats.read` and
calibrates it with :func:`accelcal.calibration.calibrate_recording` (the default static
detection, the candidates' best when it finds too few poses) and
:func:`accelcal.gyro.recording.calibrate_recording_gyro`: the command line's route, so that
the workflow's numbers are what a user gets.  The files come from manifests
(``{dataset: {file: path}}``, :func:`local_paths` for the shared copy).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

DATA = Path(__file__).resolve().parents[4] / "shared" / "data"


@dataclass(frozen=True)
class SessionSpec:
    """One session: its dataset, files, gravity, reading options and accelerometer estimator."""

    name: str
    dataset: str
    acc: str
    g: float
    gyro: str | None = None  #: a gyro file of its own (IMU-TK's layout), else the gyro columns
    read: dict = field(default_factory=dict)  #: reading options (accelcal.formats.read)
    intervals: str | None = None  #: a section list of the dataset (Ferraris sessions)
    method: str = "full_lls"
    calib: tuple = ()  #: IMU-TK's published (acc, gyro) .calib files of the dataset

    @property
    def files(self) -> tuple[str, ...]:
        return tuple(f for f in (self.acc, self.gyro, self.intervals, *self.calib) if f)


#: The sessions' table (one source with the workflow, which reads it while the Snakefile
#: is parsed to plan the fetch jobs, without importing this package).
TABLE = json.loads((Path(__file__).resolve().parents[1] / "data" / "gyro_sessions.json").read_text())
SESSIONS: dict[str, SessionSpec] = {
    name: SessionSpec(name, **{k: tuple(v) if k == "calib" else v for k, v in spec.items()})
    for name, spec in TABLE["sessions"].items()}
#: The CTU rig's gyro-only rotations (:mod:`.ferraris_sessions`): (dataset, file).
CTU = tuple(TABLE["ctu"])


def files_needed(names) -> dict[str, tuple[str, ...]]:
    """``{dataset: files}`` of the sessions ``names`` and the CTU rotations."""
    out: dict[str, list[str]] = {CTU[0]: [CTU[1]]}
    for n in names:
        s = SESSIONS[n]
        out.setdefault(s.dataset, [])
        out[s.dataset] += [f for f in s.files if f not in out[s.dataset]]
    return {k: tuple(v) for k, v in out.items()}


def local_paths(names, data_dir=DATA, resources_dir="resources") -> dict[str, dict[str, Path]]:
    """``{dataset: {file: path}}`` of the sessions ``names`` (the shared copy, else a verified download)."""
    from accelcal_repro.measured.data import fetch_dataset

    return {d: fetch_dataset(d, data_dir, resources_dir, files) for d, files in files_needed(names).items()}


def read_session(spec: SessionSpec, paths: dict):
    """The session as a Recording with its gyro (the CLI's readers and options)."""
    from accelcal.formats import read

    p = paths[spec.dataset]
    return read(p[spec.acc], gyro=p[spec.gyro] if spec.gyro else None,
                intervals=p[spec.intervals] if spec.intervals else None, **spec.read)


def calibrate_session(spec: SessionSpec, paths: dict, *, estimator: str | None = None,
                      noise_model: bool = True) -> dict:
    """Accelerometer and gyro of one session, as ``accelcal calibrate`` (module docstring), and their times."""
    from dataclasses import replace

    from accelcal.calibration import calibrate_recording
    from accelcal.gyro.recording import MIN_RESTS, calibrate_recording_gyro

    rec = read_session(spec, paths)
    t0 = time.perf_counter()
    acc, poses = calibrate_recording(rec, spec.g, spec.method, search=True, min_poses=MIN_RESTS)
    t1 = time.perf_counter()
    gyro = calibrate_recording_gyro(rec, acc, poses, estimator=estimator, noise_model=noise_model)
    t2 = time.perf_counter()
    search = acc.provenance.get("static", {}).get("search")
    return {"session": spec.name, "rec": rec, "poses": poses, "acc": replace(acc, gyro=gyro), "gyro": gyro,
            "static_note": search["description"] if search else (
                "known intervals" if rec.intervals is not None else "default detection settings"),
            "acc_seconds": t1 - t0, "gyro_seconds": t2 - t1}


__all__ = ["CTU", "DATA", "SESSIONS", "SessionSpec", "calibrate_session", "files_needed", "local_paths",
           "read_session"]
