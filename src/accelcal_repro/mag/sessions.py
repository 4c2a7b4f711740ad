"""The real magnetometer sessions: their field samples, rests (or samples near g) and the
accelerometer directions every tool is judged against.

=================  ==========================================  =====================================
session            file (``../shared/data``)                   directions for the dip
=================  ==========================================  =====================================
``snu_goodK``      snu_static3/imu_goodK.txt (K = 1, 2, 3)     accelcal's accelerometer, rest means
``ck_explorer``    mag_ck_explorer/acc_mag_log.csv             raw samples within 2 % of the median |a|
``qmc_noisy``      mag_qmc5883l_suarez/noisy_raw_data.csv      none (a magnetometer alone)
``qmc_filtered``   mag_qmc5883l_suarez/filtered_raw_data.csv   none
=================  ==========================================  =====================================
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from accelcal.calibration import calibrate_recording
from accelcal.errors import AccelcalError
from accelcal.formats import read
from accelcal.formats.mag_table import read_mag_table
from accelcal.mag.calibrate import G_TOLERANCE

#: The dataset (of :data:`accelcal_repro.measured.data.DATASETS`) and files of each session:
#: one table with the workflow, which reads it while the Snakefile is parsed (to plan the
#: fetch jobs) without importing this package.
TABLE = json.loads((Path(__file__).resolve().parents[1] / "data" / "mag_sessions.json").read_text())
FILES = {name: (e["dataset"], tuple(e["files"])) for name, e in TABLE.items()}
SESSIONS = tuple(FILES)


def files_needed(sessions) -> dict:
    """``{dataset: [files]}`` the sessions read."""
    out: dict = {}
    for s in sessions:
        ds, files = FILES[s]
        out.setdefault(ds, [])
        out[ds] += [f for f in files if f not in out[ds]]
    return out
#: Local gravity of the SNU sessions (the authors').
SNU_G = 9.79871


@dataclass
class MagSession:
    """One session: raw field ``m``; ``rest_idx`` (k, 2) rest ranges or None; ``f`` (k, 3)
    specific-force directions at the rests (or near-g samples ``sel``); the accelerometer's
    calibration and poses when it has rests; ``start`` the first sample after an initial rest."""

    name: str
    m: np.ndarray
    unit: str
    rest_idx: np.ndarray | None = None
    f: np.ndarray | None = None
    sel: np.ndarray | None = None
    acc: np.ndarray | None = None
    acc_cal: object = None
    poses: object = None
    start: int = 0
    notes: str = ""

    def points(self, m) -> np.ndarray:
        """The fields the dip is measured at: rest means, or the near-g samples."""
        m = np.asarray(m, float)
        if self.rest_idx is not None:
            return np.array([np.nanmean(m[a:b], axis=0) for a, b in self.rest_idx])
        return m[self.sel] if self.sel is not None else m[self.start:]


def load(name: str, data_dir) -> MagSession:
    d = Path(data_dir)
    if name.startswith("snu_good"):
        return _snu(name, d / "snu_static3" / f"imu_good{name[-1]}.txt")
    if name == "ck_explorer":
        t = read_mag_table(d / "mag_ck_explorer" / "acc_mag_log.csv", mag_unit="gauss", unit="g")
        na = np.linalg.norm(t.acc, axis=1)
        sel = np.abs(na - np.median(na)) <= G_TOLERANCE * np.median(na)
        return MagSession(name, t.mag, t.mag_unit, f=t.acc[sel], sel=sel, acc=t.acc,
                          notes=f"no rests: {int(sel.sum())} samples within {100 * G_TOLERANCE:g} % of the median |a|")
    if name.startswith("qmc_"):
        t = read_mag_table(d / "mag_qmc5883l_suarez" / f"{name[4:]}_raw_data.csv", mag_unit="counts")
        return MagSession(name, t.mag, t.mag_unit, start=60 * 50, notes="a magnetometer alone: 60 s rest at 50 Hz")
    raise AccelcalError(f"unknown magnetometer session {name!r}; known: {', '.join(SESSIONS)}")


def _snu(name, path) -> MagSession:
    rec = read(path, columns="ax=tx,ay=ty,az=tz")
    try:
        cal, poses = calibrate_recording(rec, SNU_G, "full_lls", search=True)
        how = "full-lls"
    except AccelcalError:  # good1: 8 distinct orientations, too few for the full model
        cal, poses = calibrate_recording(rec, SNU_G, "bias_lls", search=True)
        how = "bias-lls (too few orientations for the full model)"
    keep = ~np.all(rec.mag == 0, axis=1)
    m = np.where(keep[:, None], rec.mag, np.nan)  # the first row's zeros: no reading yet
    iv = np.asarray(poses.intervals, int)
    f = cal.apply(np.asarray(poses.means))
    return MagSession(name, m, rec.mag_unit, rest_idx=iv, f=f, acc=rec.acc, acc_cal=cal, poses=poses,
                      start=int(np.argmax(keep)) if poses.reference != "initial_rest" else int(poses.init_rest[1]),
                      notes=f"{len(iv)} rests, accelerometer {how}")


__all__ = ["FILES", "MagSession", "SESSIONS", "files_needed", "load"]
