"""Adding an effect of an existing kind: one entry of the effect table.

A fourth-power nonlinearity ``P_j(x) = x_j + q_j x_j⁴`` is a polynomial effect like the
quadratic and cubic ones, so its entry is all the model needs: the forward model, the
fits' residuals and Jacobian (numpy and compiled), the discrepancy loop and the inverse
``Calibration.apply`` uses all read the table (:mod:`accelcal.extended_model`).  In the
package the entry is one more item of ``EFFECTS`` in ``accelcal/effects.py``
(docs/extending.md); here it is put in at run time.

Run: ``python examples/custom_effect.py``.
"""

from __future__ import annotations

import sys

import numpy as np

from accelcal.calibration import EffectTerm, ExtendedCalibration
from accelcal.discrepancy import Rules, discrepancy, pose_data
from accelcal.effects import EFFECT_IDS, EFFECTS, POLYNOMIAL, Effect
from accelcal.extended_model import forward
from accelcal.simulation import random_directions

G = 9.80665

QUARTIC = Effect(id="quartic", kind=POLYNOMIAL, power=4, covariate=None, symbol="q", unit="1/G^3",
                 label="quartic", description="per-axis nonlinearity x_j + q_j x_j^4")


def main() -> int:
    EFFECTS[QUARTIC.id] = QUARTIC
    rng = np.random.default_rng(3)
    n = 60
    x = G * random_directions(rng, n)  # the true specific force of 60 rests
    t = np.sort(rng.uniform(0.0, 600.0, n))
    q = 1e-6 * np.array([1.0, -1.0, 1.0])  # about 9 mm/s² at |x| = g: 9 times the noise of a pose mean
    z = forward(x, np.eye(3), np.zeros(3), {"quartic": q}, {})
    se = np.full((n, 3), 1e-3)
    data = pose_data(z + se * rng.standard_normal((n, 3)), G, se, t)

    # the discrepancy loop tests it beside the library's effects, and names it
    result = discrepancy(data, Rules(null="white", candidates=(*EFFECT_IDS, "quartic")))
    print(result.summary())

    # a calibration that carries it inverts the model
    cal = ExtendedCalibration(bias=np.zeros(3), M=np.eye(3), g=G, unit="m/s^2", effects=(EffectTerm("quartic", q),))
    error = np.max(np.abs(cal.apply(z) - x))
    without = np.max(np.abs(cal.apply(z, effects=False) - x))
    print(f"apply: largest error {error:.1e} m/s^2 over {n} rests ({without:.1e} without the effect)")
    return 0 if result.effects == ("quartic",) and error < 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
