"""Adding a wander process: one class, registered, with all its behaviour on it.

The process: a wander whose time scale the session cannot tell.  REML names a Gauss–Markov
wander, but its correlation time's 95 % interval runs from 0 (a per-placement offset) to
no upper bound (a random walk): the session shows extra noise between the poses and no
more.  Its covariance, Allan variance and simulation are the Gauss–Markov estimate's (the
entry reuses that entry's); what is its own is when it is named, its name in the report's
JSON and its reading.  Once registered, the discrepancy report names it, reads it back
from its JSON (``process`` key), the reproductions simulate it and the report schema
accepts it; ``tests/test_wander_process_conformance.py`` checks it as every other process
(``tests/test_examples.py`` runs those checks on it).  In the package the class is one
more entry of ``src/accelcal/discrepancy/wander_process.py``.

Run: ``python examples/custom_wander_process.py``.
"""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np

from accelcal.discrepancy.schema import check_statuses
from accelcal.discrepancy.wander import WanderFit, gm_variance
from accelcal.discrepancy.wander_model import noise_model_dict
from accelcal.discrepancy.wander_process import PROCESSES, WanderProcess, process_in, register_process
from accelcal.jsonsafe import json_safe

GM = PROCESSES["gauss_markov"]


@register_process
class UnresolvedWander(WanderProcess):
    id, label, noise_term = "unresolved_wander", "wander of unknown time scale", GM.noise_term
    meaning = "a Gauss-Markov estimate whose tau interval runs from 0 to no upper bound: size only"
    parameters = {"size": "std of the noise between the poses per axis (data unit)"}
    example = {"tau": 6.0, "q_abs": 3.3e-6, "tau_ci": (0.0, math.inf)}

    def matches(self, w, span):  # a later entry refines an earlier one: it is asked first
        lo, hi = (list(w.tau_ci) + [math.nan] * 2)[:2]
        return GM.matches(w, span) and lo == 0 and not np.isfinite(hi)

    def time_correlated(self, w, shortest):
        return False

    def model_entry(self, w):
        return GM.model_entry(w)

    def components(self, nm):
        return GM.components(nm)

    def rest_allan(self, nm):
        return GM.rest_allan(nm)

    def reading(self, nm, words):
        return (f"noise between the poses of {words.size(nm.get('size'))} per axis, time scale not determined "
                f"(its correlation time's interval holds a per-placement offset and a random walk alike)"
                f"{words.axes}{words.white}")

    def cell(self, nm, g):
        return f"size {g(nm.get('size'))}, time scale not determined", f"size [{', '.join(map(g, nm['size_ci']))}]"


if __name__ == "__main__":
    # the REML estimate the loop reported on the IMU-TK fork's data3 session (CI config):
    # τ 5.97 s with the interval [0, ∞), size 1.82e-3 in the data unit, over a 108 s session
    tau, size = 5.967, 1.821e-3
    _, K = gm_variance(size**2, tau)
    w = WanderFit(t=0, q_rel=0.4, tau=tau, q_abs=size**2, size=size, K=K, white_scale=1.1, reml=0.0,
                  size_ci=(0.0, 4.1e-3), tau_ci=(0.0, math.inf), K_ci=(0.0, math.inf), white_scale_ci=(0.6, 1.9),
                  excess_ci=(1.0, 1.4), at_bound=(), common=0.0, common_ci=(0.0, 0.5))
    prob = SimpleNamespace(durations=np.full(33, 1.5), span=108.1, notes=())
    nm = json.loads(json.dumps(json_safe(noise_model_dict(w, prob))))  # as the report's JSON holds it
    check_statuses({"noise_model": nm})
    print(f"process: {nm['process']} ({process_in(nm).label})")
    print(f"reading: {nm['reading']}")
    print(f"simulated as: {process_in(nm).components(nm)}")
