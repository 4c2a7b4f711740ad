"""The one registry of export consumers: the estimators' and autopilots' files accelcal writes.

Everything that chooses or describes a consumer reads it from here: ``accelcal export --to``
(its choices and help), :func:`accelcal.export.api.export` and the conformance suite
(``tests/test_export_conformance.py``, parametrised over :data:`CONSUMERS`).  Writers are
named ``module:function`` and imported on first use, so that ``accelcal --help`` imports
no numerical library.

A consumer's writer is ``f(inputs: ExportInputs) -> Export``.  A file that holds several
sensors (an autopilot's parameter file) is built from *sections*, one per sensor: a
section is ``f(inputs) -> (lines, left_out, notes)`` and another part of accelcal (the
magnetometer's compass parameters) adds its own with :func:`add_section`, without
touching the consumer's module; the writer asks :func:`sections` for all of them.

Adding a consumer: a module in this package with its writer, one entry below, and a test
that corrects raw data as the consumer's own source does (cite repository, file, line)
and checks it against ``accelcal apply``.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

from ..registry import resolve

#: What a consumer may need beyond the accelerometer.
NEEDS = ("gyro", "noise")


@dataclass(frozen=True, kw_only=True)
class Consumer:
    """One consumer of an export.

    Attributes
    ----------
    name : str
        The ``--to`` value.
    title : str
        What the file is, one line for the CLI's help.
    writer : str
        ``'module:function'`` of ``f(inputs) -> Export``.
    needs : tuple of str
        Of :data:`NEEDS`: the parts without which nothing can be written.
    files : tuple of str
        The suffixes of the files written beside the user's path ('' for the path itself).
    source : str
        Where the consumer's own equations are (repository and file), which its test follows.
    options : tuple of str
        The export options it reads (``rostopic``, ``inflate``, ``instance``, ``model`` ...).
    sections : tuple of str
        ``'module:function'`` of its built-in sections (param files), in order.
    """

    name: str
    title: str
    writer: str
    needs: tuple[str, ...] = ()
    files: tuple[str, ...] = ("",)
    source: str = ""
    options: tuple[str, ...] = ()
    sections: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self):
        if set(self.needs) - set(NEEDS):
            raise ValueError(f"consumer {self.name}: unknown needs {sorted(set(self.needs) - set(NEEDS))}")

    def load_writer(self):
        return resolve(self.writer)


_E = "accelcal.export"

#: The consumers, by name, in the order the help lists them.
CONSUMERS: dict[str, Consumer] = {c.name: c for c in (
    Consumer(name="kalibr", title="Kalibr imu.yaml: noise densities and random walks, and the IMU intrinsics of its "
                                  "scale-misalignment model (accelerometers M, gyroscopes M, A, C_gyro_i)",
             writer=f"{_E}.kalibr:write", needs=("noise",), options=("rostopic", "inflate"),
             source="ethz-asl/kalibr aslam_offline_calibration/kalibr/python/kalibr_imu_camera_calibration/"
                    "IccSensors.py"),
    Consumer(name="openvins", title="OpenVINS kalibr_imu_chain.yaml: noise, Tw, R_IMUtoGYRO, Ta, R_IMUtoACC, Tg "
                                    "(--model kalibr or rpng)",
             writer=f"{_E}.openvins:write", needs=("noise",), options=("rostopic", "inflate", "model"),
             source="rpng/open_vins ov_msckf/src/state/Propagator.cpp, ov_msckf/src/core/VioManagerOptions.h"),
    Consumer(name="vins", title="VINS-Mono / VINS-Fusion config: acc_n, gyr_n, acc_w, gyr_w, g_norm",
             writer=f"{_E}.vins:write", needs=("noise",), options=("inflate",),
             source="HKUST-Aerial-Robotics/VINS-Fusion vins_estimator/src/factor/integration_base.h"),
    Consumer(name="orbslam3", title="ORB-SLAM3 settings: IMU.NoiseGyro, IMU.NoiseAcc, IMU.GyroWalk, IMU.AccWalk, "
                                    "IMU.Frequency",
             writer=f"{_E}.orbslam3:write", needs=("noise",), options=("inflate",),
             source="UZ-SLAMLab/ORB_SLAM3 src/Tracking.cc"),
    Consumer(name="kfgins", title="KF-GINS config: initial IMU errors (bias, scale) and imunoise (ARW, VRW, bias std, "
                                  "scale std, correlation time)",
             writer=f"{_E}.kfgins:write", needs=("gyro", "noise"), options=("corr_time_h",),
             source="i2Nav-WHU/KF-GINS src/kf-gins/gi_engine.cpp, src/kf_gins.cpp"),
    Consumer(name="px4", title="PX4 parameter file (.params, QGroundControl's layout): CAL_ACCn_xOFF/xSCALE, "
                               "CAL_GYROn_xOFF, CAL_MAGn_xOFF/xSCALE/xODIAG",
             writer=f"{_E}.px4:write", options=("instance", "device_id"),
             sections=(f"{_E}.px4:accelerometer_section", f"{_E}.px4:gyroscope_section",
                       "accelcal.mag.export:px4_section"),
             source="PX4/PX4-Autopilot src/lib/sensor_calibration/Accelerometer.hpp, Gyroscope.hpp"),
    Consumer(name="ardupilot", title="ArduPilot parameter file (.parm): INS_ACCOFFS_x, INS_ACCSCAL_x, INS_GYROFFS_x, "
                                     "COMPASS_OFS_x, COMPASS_DIA_x, COMPASS_ODI_x, COMPASS_SCALE",
             writer=f"{_E}.ardupilot:write", options=("instance",),
             sections=(f"{_E}.ardupilot:accelerometer_section", f"{_E}.ardupilot:gyroscope_section",
                       "accelcal.mag.export:ardupilot_section"),
             source="ArduPilot/ardupilot libraries/AP_InertialSensor/AP_InertialSensor_Backend.cpp"),
    Consumer(name="imutk", title="IMU-TK .calib files (PATH_acc.calib, PATH_gyro.calib): x = T K (raw - b)",
             writer=f"{_E}.imutk:write", files=("_acc.calib", "_gyro.calib"),
             source="ethz-asl/imu_tk src/calibration.cpp (CalibratedTriad_)"),
    Consumer(name="imucal", title="imucal FerrarisCalibrationInfo JSON (accelerometer and gyroscope)",
             writer=f"{_E}.imucal:write", needs=("gyro",),
             source="mad-lab-fau/imucal imucal/ferraris_calibration_info.py"),
)}

#: Sections other parts of accelcal add to a consumer's file (:func:`add_section`).
_ADDED: dict[str, list[str]] = {}


def add_section(consumer: str, function: str) -> None:
    """Add ``'module:function'`` (``f(inputs) -> (lines, left_out, notes)``) to ``consumer``'s file,
    after its own sections; adding the same one twice adds it once."""
    if consumer not in CONSUMERS:
        raise KeyError(f"unknown export consumer {consumer!r}")
    added = _ADDED.setdefault(consumer, [])
    if function not in added:
        added.append(function)


def sections(consumer: str) -> list:
    """The section functions of ``consumer``'s file: its own, then the added ones."""
    return [resolve(f) for f in (*CONSUMERS[consumer].sections, *_ADDED.get(consumer, ()))]


def consumer_named(name: str) -> Consumer:
    from .base import ExportError

    try:
        return CONSUMERS[name]
    except (KeyError, TypeError):
        raise ExportError(f"unknown export target {name!r}; known: {', '.join(CONSUMERS)}") from None


def consumers_help(width: int = 80) -> str:
    """The consumers as help text: name, title and what each needs."""
    lines = ["targets (--to):"]
    column = max(len(n) for n in CONSUMERS) + 4
    for c in CONSUMERS.values():
        text = c.title + (f"; needs {' and '.join('--noise' if n == 'noise' else 'a gyroscope' for n in c.needs)}"
                          if c.needs else "")
        lines += textwrap.wrap(text, width, initial_indent=f"  {c.name}".ljust(column),
                               subsequent_indent=" " * column, break_on_hyphens=False)
    return "\n".join(lines)


__all__ = ["CONSUMERS", "Consumer", "NEEDS", "add_section", "consumer_named", "consumers_help", "sections"]
