"""Adding an estimator: a function, its calibration class and one registry entry.

The estimator fits the bias-only model (``M = I``) by Gauss-Newton on
``Σ (|z_i - b| - g)²``, started from the algebraic fit.  Once registered it is a method of
``accelcal calibrate`` (``--method bias-gn``) whose calibration files save and load as
every other's.  In the package the function and its class are one module, and the entry
one item of ``ESTIMATORS`` in ``accelcal/registry.py`` (docs/extending.md).

Run: ``python examples/custom_estimator.py``.
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from accelcal import cli
from accelcal.calibration import Calibration, load_calibration
from accelcal.registry import PoseEstimator, register
from accelcal.results import NLLSResult
from accelcal.simulation import random_directions, simulate_recording
from accelcal.validation import check_g, check_poses


def bias_gn(z, g: float) -> NLLSResult:
    """Bias-only model by Gauss-Newton from the algebraic fit.

    Parameters
    ----------
    z : array_like, shape (n, 3)
        Static pose means.
    g : float
        Gravity magnitude, unit of ``z``.
    """
    z, g = check_poses(z, "bias"), check_g(g)  # the typed errors every estimator raises
    A = np.column_stack([2 * z, np.ones(len(z))])
    b = np.linalg.lstsq(A, np.sum(z * z, axis=1), rcond=None)[0][:3]  # |z - b|² = g²: linear in (b, c)
    for iterations in range(1, 51):
        d = z - b
        r = np.linalg.norm(d, axis=1)
        step = np.linalg.lstsq(-d / r[:, None], g - r, rcond=None)[0]
        b = b + step
        if np.abs(step).max() <= 1e-13 * g:
            break
    cost = float(np.sum((np.linalg.norm(z - b, axis=1) - g) ** 2))
    return NLLSResult(method="bias_gn", bias=b, M=np.eye(3), g=g, poses=z, status="converged",
                      iterations=iterations, cost=cost)


@dataclass(frozen=True, eq=False)
class BiasGNCalibration(Calibration):
    """Its calibration: the base class's fields, and the result's fields it keeps (taken from
    the estimator's result by name, written to and read from the JSON)."""

    CAL_TYPE: ClassVar[str] = "bias_gn"
    iterations: int = 0
    cost: float = float("nan")


ENTRY = PoseEstimator(name="bias_gn", model="bias", algorithm="gn", label="bias-only Gauss-Newton",
                      family="iterative", function=f"{__name__}:bias_gn", calibration=f"{__name__}:BiasGNCalibration",
                      baseline="bias_nlls", conditioning="accelcal.lls:design_singular_values", min_poses=4,
                      description="Gauss-Newton from the algebraic fit, M = I")


def main(folder: Path) -> int:
    register(ENTRY)
    # a recording of 16 rests, the sensor's only error a bias of a few mg
    rng = np.random.default_rng(5)
    bias = np.array([0.012, -0.009, 0.011])
    rec = simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, 15)]), 9.80665, np.eye(3), bias,
                             noise_std=0.01)
    path = folder / "session.csv"
    np.savetxt(path, np.column_stack([rec["t"], rec["acc"]]), delimiter=",", header="t,ax,ay,az", comments="")

    code = cli.main(["calibrate", str(path), "--g", "9.80665", "--method", "bias-gn", "--out",
                     str(folder / "cal.json")])  # prints the calibration's summary
    cal = load_calibration(folder / "cal.json")
    print(f"{type(cal).__name__}: bias {np.round(cal.bias, 4)} after {cal.iterations} iterations "
          f"(true {bias})")
    return code if np.allclose(cal.bias, bias, atol=3e-3) and isinstance(cal, BiasGNCalibration) else 1


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        sys.exit(main(Path(tmp)))
