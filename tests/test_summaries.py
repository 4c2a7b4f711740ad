"""Results render their own summary: what `accelcal calibrate` and `accelcal discrepancy`
print is the result's ``summary()``, also for a calibration read back from its file."""

import ast
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from accelcal import cli
from accelcal.calibration import calibrate_poses, load_calibration
from accelcal.discrepancy import report
from accelcal.formats import read
from accelcal.simulation import random_directions, sample_truth, simulate_recording
from accelcal.static import detect_static_recording

G = 9.80665
QUICK = report.StochasticSettings(n_boot=19, n_resim=1)


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    rng = np.random.default_rng(3)
    tr = {k: v[0] for k, v in sample_truth(rng, 1).items()}
    u = np.vstack([[0, 0, 1.0], random_directions(rng, 29)])
    rec = simulate_recording(rng, u, G, tr["M"], tr["bias"], noise_std=0.01, temperature=(20.0, 25.0))
    path = tmp_path_factory.mktemp("rec") / "session.csv"
    pd.DataFrame({"t": rec["t"], "ax": rec["acc"][:, 0], "ay": rec["acc"][:, 1], "az": rec["acc"][:, 2],
                  "temp": rec["temp"]}).to_csv(path, index=False)
    return path


def _without_progress(err: str) -> str:
    """stderr without the progress lines a slow step prints after 2 s (cli.common._step): on a loaded
    machine they appear, and they are not the summary."""
    return "".join(line for line in err.splitlines(keepends=True)
                   if not (line.startswith("accelcal: ") and line.rstrip().endswith(" ...")))


def _initial_rest_s(path) -> float:
    rec = read(path)
    poses = detect_static_recording(rec)
    assert poses.reference == "initial_rest"
    return rec.t[poses.init_rest[1] - 1] - rec.t[0]


@pytest.mark.parametrize("extra", [["--g", str(G)], ["--method", "bias-lls"], ["--method", "full-als", "--g", "9.81"]])
def test_calibrate_prints_the_calibrations_summary(session, tmp_path, capsys, extra):
    out = tmp_path / "cal.json"
    assert cli.main(["calibrate", str(session), "--out", str(out), *extra]) == 0
    err = _without_progress(capsys.readouterr().err)
    cal = load_calibration(out)  # the file keeps what the summary needs (notes, noise reference, g source)
    assert err == cal.summary(init_rest_s=_initial_rest_s(session), written_to=out) + "\n"
    lines = err.splitlines()
    assert lines[0].startswith(f"{cal.to_dict()['method']}: 30 poses (noise reference: initial rest (0-")
    assert ("standard gravity" in lines[0]) == ("--g" not in extra)
    # the reader's notes, then the command's own on the gyro (this session has none)
    assert [ln for ln in lines if ln.startswith("  read: ")] == [f"  read: {n}" for n in read(session).notes] + [
        "  read: no gyro columns: the accelerometer alone (a gyro in a file of its own: --gyro FILE)"]
    assert lines.index(f"  written to {out}") == len(lines) - 1 - len(cal.quality.warnings)
    assert lines[len(lines) - len(cal.quality.warnings):] == [f"warning: {w}" for w in cal.quality.warnings]


def test_a_calibration_made_by_the_library_summarises_itself(session):
    """No CLI context: no noise reference, no output line; a quality warning still shows."""
    poses = detect_static_recording(read(session))
    cal = calibrate_poses(poses, G, "full_lls", unit="m/s^2")
    text = cal.summary()
    assert text.splitlines()[0] == f"full-lls: 30 poses; data in m/s^2; g = {G:g} m/s^2"
    assert "written to" not in text and "  scale [ppm]" in text and "  nonorth [deg]" in text
    small = calibrate_poses(_subset(poses, 12), G, "full_lls", unit="m/s^2")
    assert "warning: only 3 degree(s) of freedom" in small.summary()


def _subset(poses, n):
    from dataclasses import replace

    keep = slice(0, n)
    return replace(poses, means=poses.means[keep], t_start=poses.t_start[keep], t_end=poses.t_end[keep],
                   t_mid=poses.t_mid[keep], n_samples=poses.n_samples[keep], noise_std=poses.noise_std[keep],
                   mean_std=poses.mean_std[keep], temp=None if poses.temp is None else poses.temp[keep],
                   intervals=poses.intervals[keep])


def test_one_summary_type_with_three_renderers():
    """Every result the command line prints answers summary(written_to=...) with a Summary: its text
    is the str itself, and its dict and HTML say the same (title, body, warnings)."""
    import html

    from accelcal.summary import Summary

    s = Summary(["gyroscope: gyro_iterative", "  scale factors [ppm]: x +12 ± 3", "warning: gyroscope: few motions",
                 "written to c.json"])
    assert s == "gyroscope: gyro_iterative\n  scale factors [ppm]: x +12 ± 3\nwarning: gyroscope: few motions\n" \
                "written to c.json" and s + "\n" == str(s) + "\n" and s.as_text() == str(s)
    assert s.as_dict() == {"title": "gyroscope: gyro_iterative",
                           "lines": ["  scale factors [ppm]: x +12 ± 3", "written to c.json"],
                           "warnings": ["gyroscope: few motions"]}
    h = s.as_html()
    assert h.startswith('<section class="summary"><h4>gyroscope: gyro_iterative</h4>')
    assert html.escape("gyroscope: few motions") in h and "± 3" in h


def test_every_result_type_returns_a_summary():
    import inspect

    from accelcal.calibration.base import Calibration
    from accelcal.discrepancy.gyro_loop import GyroLoopResult
    from accelcal.discrepancy.mag_loop import MagLoopResult
    from accelcal.discrepancy.results import DiscrepancyReport, DiscrepancyResult
    from accelcal.gyro.result import GyroCalibration
    from accelcal.mag.result import MagCalibration
    from accelcal.noise.report import NoiseReport

    # the loops' results are lines of the discrepancy report's summary
    results = (Calibration, GyroCalibration, MagCalibration, DiscrepancyReport, DiscrepancyResult, NoiseReport,
               GyroLoopResult, MagLoopResult)
    for cls in results:
        sig = inspect.signature(cls.summary)
        assert "written_to" in sig.parameters and sig.parameters["written_to"].kind is inspect.Parameter.KEYWORD_ONLY
        assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for name, p in sig.parameters.items() if name != "self"), \
            (cls.__name__, sig)  # one signature: what a type adds is a keyword
        assert sig.return_annotation in ("Summary", "Summary"), (cls.__name__, sig.return_annotation)
    assert classes_with_a_summary(SRC / "accelcal") == sorted(c.__name__ for c in results)


SRC = Path(__file__).resolve().parents[1] / "src"


def classes_with_a_summary(root: Path) -> list[str]:
    """The classes under ``root`` that define a ``summary`` method (files parsed, not imported)."""
    return sorted(node.name for path in root.rglob("*.py") for node in ast.walk(ast.parse(path.read_text()))
                  if isinstance(node, ast.ClassDef)
                  and any(isinstance(m, ast.FunctionDef) and m.name == "summary" for m in node.body))


def test_the_summary_census_sees_a_new_result_type(tmp_path):
    (tmp_path / "m.py").write_text("class Fit:\n    def summary(self):\n        return ''\n\n\ndef summary():\n    pass\n")
    assert classes_with_a_summary(tmp_path) == ["Fit"]
