"""The measured recordings: which files, which reader, which unit and nominal conversion.

The public recordings (``shared/data/README.md``), named by what they are:

====================  =======================  ======  ====================================================
name                  dataset                  unit    content
====================  =======================  ======  ====================================================
``xsens_mti``         ``imu_tk_xsens``         counts  Xsens MTi, ~38 hand-placed poses (IMU-TK)
``mpu6050``           ``mpu6050_suarez``       counts  MPU-6050, ~10 hand-placed poses
``imucal_ferraris``   ``imucal_ferraris``      m/s²    Ferraris session: 6 static positions and 3 rotations
``imutk_fork_data2``  ``imutk_fork_sessions``  m/s²    one IMU (ROS topic), 40 hand-placed poses
``imutk_fork_data3``  ``imutk_fork_sessions``  m/s²    the same IMU, 27 poses
``imutk_fork_data4``  ``imutk_fork_sessions``  m/s²    the same IMU, 22 poses
``fxos8700_sample1``  ``fastahrs_fxos8700``    m/s²    FXOS8700 block log, 18 blocks = known rests
``fxos8700_sample2``  ``fastahrs_fxos8700``    m/s²    FXOS8700 block log, 20 blocks = known rests
====================  =======================  ======  ====================================================

The fork sessions do not start at rest (the first seconds are 6-9x noisier than the
later rests), so the static detection takes its noise level from their quietest stretch
(:func:`accelcal.static.detect_static`, ``noise_reference='auto'``).  The FXOS8700 logs
have no time stamps and no motion between poses; each block is a known static interval
(:func:`accelcal.formats.block_log.read_block_log`), carried into the canonical CSV as its
``pose`` column, so no detection runs on them.

:func:`read_source` reads the original file with the readers of
:mod:`accelcal.formats`; :func:`convert` writes the canonical CSV of the CLI
(``t,ax,ay,az``), which is what the calibration step reads.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from accelcal.atomic import atomic_output, sha256_file, write_json_atomic
from accelcal.errors import RecordingError
from accelcal.formats import read, write_recording
from accelcal.formats.intervals import read_imucal_section_list
from accelcal.nominal import NominalConversion, nominal_conversion
from accelcal.recording import Recording
from .data import fetch_file


@dataclass(frozen=True)
class Source:
    """One measured recording.

    Attributes
    ----------
    name : str
        Name used in file names and tables.
    dataset : str
        Folder of ``shared/data`` (key of :data:`accelcal_repro.measured.data.DATASETS`).
    data_file : str
        The accelerometer recording.
    extra_files : tuple of str
        Other files the analysis needs (the imucal section list).
    fmt : str
        The format the file is read as (:data:`accelcal.formats.FORMATS`), the one
        ``accelcal calibrate`` detects: IMU-TK ASCII files are read as tables (``csv``).
    nominal : str
        Key of :func:`accelcal.nominal.nominal_conversion`.
    unit : str
        Unit of the file's acceleration values, ``'counts'`` or ``'m/s^2'``.
    description : str
    """

    name: str
    dataset: str
    data_file: str
    extra_files: tuple[str, ...]
    fmt: str
    nominal: str
    unit: str
    description: str

    @property
    def files(self) -> tuple[str, ...]:
        return (self.data_file, *self.extra_files)

    @property
    def conversion(self) -> NominalConversion:
        return nominal_conversion(self.nominal)


SOURCES: dict[str, Source] = {
    "xsens_mti": Source("xsens_mti", "imu_tk_xsens", "xsens_acc.mat", (), "csv", "imutk_xsens", "counts",
                        "Xsens MTi, IMU-TK example session (hand-placed static poses)"),
    "mpu6050": Source("mpu6050", "mpu6050_suarez", "example_data_calibration.csv", (), "mpu6050", "mpu6050",
                      "counts", "InvenSense MPU-6050, tomisuarez2/ImuCalibration example (hand-placed poses)"),
    "imucal_ferraris": Source("imucal_ferraris", "imucal_ferraris", "example_ferraris_session.csv",
                              ("example_ferraris_session_list.json",), "imucal", "imucal_session", "m/s^2",
                              "imucal example Ferraris session (six static positions, three rotations)"),
    **{f"imutk_fork_{d}": Source(f"imutk_fork_{d}", "imutk_fork_sessions", f"{d}/acc_data.txt", (), "csv",
                                 "imutk_fork", "m/s^2",
                                 f"IMU-TK fork (GetOverMassif) session {d}: one ROS IMU, hand-placed static poses")
       for d in ("data2", "data3", "data4")},
    **{f"fxos8700_sample{k}": Source(f"fxos8700_sample{k}", "fastahrs_fxos8700", f, (), "block-log", "fxos8700",
                                     "m/s^2", f"NXP FXOS8700 (FastAhrs {f}): poses logged as blocks, known rests")
       for k, f in ((1, "data_sample.csv"), (2, "data_sample2.csv"))},
}

#: The static sections of a Ferraris session list, in imucal's order.
FERRARIS_STATIC = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")


def source(name: str) -> Source:
    """The :class:`Source` called ``name``; :class:`RecordingError` if unknown."""
    try:
        return SOURCES[name]
    except KeyError:
        raise RecordingError(f"unknown measured recording {name!r}; known: {', '.join(SOURCES)}") from None


def fetch_source(name: str, data_dir=None, resources_dir="resources") -> dict[str, Path]:
    """Local paths of every file of recording ``name`` (see :func:`accelcal_repro.measured.data.fetch_file`)."""
    s = source(name)
    return {f: fetch_file(s.dataset, f, data_dir, resources_dir) for f in s.files}


def dataset_manifest(dataset: str, paths: dict[str, Path]) -> dict:
    """JSON-ready record of where each file of ``dataset`` was taken from and its verified sha256
    (:func:`read_manifest` reads it back)."""
    return {"dataset": dataset, "files": {f: {"path": str(p), "sha256": sha256_file(p)} for f, p in paths.items()}}


def manifest(name: str, paths: dict[str, Path]) -> dict:
    """:func:`dataset_manifest` of recording ``name``, with its unit and description."""
    s = source(name)
    return {"recording": name, "dataset": s.dataset, "unit": s.unit, "description": s.description,
            "files": dataset_manifest(s.dataset, paths)["files"]}



def read_manifest(path) -> dict[str, Path]:
    """``{file: path}`` from a manifest written by :func:`manifest`."""
    try:
        m = json.loads(Path(path).read_text())
        return {f: Path(v["path"]) for f, v in m["files"].items()}
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise RecordingError(f"{path}: not a measured-data manifest ({type(e).__name__})") from None


def read_source(name: str, paths: dict[str, Path]) -> Recording:
    """Read the original accelerometer file of recording ``name`` (units as stored) with the
    readers of ``accelcal calibrate`` (:func:`accelcal.formats.read`), so that the workflow
    and the CLI see the same numbers."""
    s = source(name)
    return read(paths[s.data_file], format=s.fmt, unit=_UNIT[s.unit])


_UNIT = {"counts": "counts", "m/s^2": "m/s2"}


def section_list(name: str, paths: dict[str, Path]) -> dict[str, tuple[int, int]] | None:
    """The imucal section list of ``name`` (half-open sample ranges), None if it has none."""
    s = source(name)
    js = [f for f in s.extra_files if f.endswith(".json")]
    return read_imucal_section_list(paths[js[0]]) if js else None


def convert(name: str, paths: dict[str, Path], out_csv) -> Recording:
    """Read recording ``name`` and write it as canonical CSV ``t,ax,ay,az`` (atomically)."""
    rec = read_source(name, paths)
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    write_recording(out_csv, rec)
    return rec


__all__ = ["FERRARIS_STATIC", "SOURCES", "Source", "convert", "dataset_manifest", "fetch_source", "manifest",
           "read_manifest", "read_source", "section_list", "source"]
