"""Adding an estimator touches one file: this one.  A toy estimator (the bias-only model
fitted by Gauss-Newton from the algebraic solution, in numpy) and its calibration class
are defined here and registered; from the registry alone it then is a name of the
package (``accelcal.bias_gn``), passes the conformance checks, runs from the command line
(``--method bias-gn``), saves and loads its calibration file, and runs in the Monte Carlo.  In the package, the same is one module
(the function and its calibration class) and one entry of ``accelcal.registry``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from accelcal import cli
from accelcal.calibration import Calibration, load_calibration
from accelcal.registry import ESTIMATORS, PoseEstimator, register, unregister
from accelcal.results import NLLSResult
from accelcal.simulation import random_directions, sample_truth, simulate_recording
from accelcal.validation import check_g, check_poses

from .test_estimator_conformance import CHECKS, run_check

G = 9.80665


def bias_gn(z, g: float) -> NLLSResult:
    """Bias-only model: Gauss-Newton on ``Σ (|z_i - b| - g)²`` from the algebraic fit (eq. 7)."""
    z, g = check_poses(z, "bias"), check_g(g)
    A = np.column_stack([2 * z, np.ones(len(z))])
    b = np.linalg.lstsq(A, np.sum(z * z, axis=1), rcond=None)[0][:3]
    for it in range(1, 51):
        d = z - b
        r = np.linalg.norm(d, axis=1)
        J = -d / r[:, None]
        step = np.linalg.lstsq(J, -(r - g), rcond=None)[0]
        b = b + step
        if np.abs(step).max() <= 1e-13 * g:
            break
    cost = float(np.sum((np.linalg.norm(z - b, axis=1) - g) ** 2))
    return NLLSResult._trusted(method="bias_gn", bias=b, M=np.eye(3), g=g, poses=z, status="converged",
                               iterations=it, cost=cost)


@dataclass(frozen=True, eq=False)
class BiasGNCalibration(Calibration):
    """The toy's calibration: it keeps the iterations and the final cost."""

    CAL_TYPE: ClassVar[str] = "bias_gn"
    iterations: int = 0
    cost: float = float("nan")


TOY = PoseEstimator(name="bias_gn", model="bias", algorithm="gn", label="bias-only Gauss-Newton", family="iterative",
                function=f"{__name__}:bias_gn", calibration=f"{__name__}:BiasGNCalibration", baseline="bias_nlls",
                conditioning="accelcal.lls:design_singular_values", min_poses=4,
                description="Gauss-Newton from the algebraic fit, M = I (a test's toy)")


@pytest.fixture(scope="module")
def toy():
    register(TOY)
    yield ESTIMATORS["bias_gn"]
    unregister("bias_gn")


def test_the_toy_is_a_name_of_the_package(toy):
    import accelcal

    try:
        assert accelcal.bias_gn is bias_gn  # from the registry, no list of names edited
    finally:
        vars(accelcal).pop("bias_gn", None)


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_toy_passes_every_conformance_check(toy, check, tmp_path):
    run_check(check, toy, tmp_path)


def test_the_toy_runs_from_the_command_line(toy, tmp_path, capsys):
    rng = np.random.default_rng(5)
    tr = {k: v[0] for k, v in sample_truth(rng, 1, identity_m=True).items()}
    rec = simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, 15)]), G, np.eye(3), tr["bias"],
                             noise_std=0.01)
    path = tmp_path / "session.csv"
    np.savetxt(path, np.column_stack([rec["t"], rec["acc"]]), delimiter=",", header="t,ax,ay,az", comments="")
    assert cli.main(["calibrate", str(path), "--g", str(G), "--method", "bias-gn", "--out",
                     str(tmp_path / "cal.json")]) == 0
    assert capsys.readouterr().err.startswith("bias-gn: 16 poses")  # the summary names it
    assert "bias-gn" in cli._methods_help()  # and the help lists it
    d = json.loads((tmp_path / "cal.json").read_text())
    assert d["cal_type"] == "bias_gn" and d["iterations"] >= 1
    cal = load_calibration(tmp_path / "cal.json")
    assert type(cal) is BiasGNCalibration
    np.testing.assert_allclose(cal.bias, tr["bias"], atol=3e-3)


