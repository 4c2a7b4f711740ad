"""The one JSON-safe conversion (accelcal.jsonsafe.json_safe) used by every JSON writer."""

import json

import numpy as np

from accelcal.jsonsafe import json_safe


def test_numpy_and_non_finite_values_become_strict_json():
    obj = {"a": np.array([[1.0, np.nan], [np.inf, -np.inf]]), "t": (np.float32(0.5), np.int64(2)),
           "flag": np.bool_(False), "nested": [{"x": float("nan")}], 3: "int key", "s": "text", "none": None}
    out = json_safe(obj)
    assert out == {"a": [[1.0, None], [None, None]], "t": [0.5, 2], "flag": False, "nested": [{"x": None}],
                   "3": "int key", "s": "text", "none": None}
    assert [type(v) for v in out["t"]] == [float, int] and type(out["flag"]) is bool
    json.dumps(out, allow_nan=False)  # strict JSON: raises on NaN or a numpy type


def test_the_calibration_result_and_file_use_it():
    """A result's to_dict holds no NaN token (the bias-only LLS has no λ: NaN)."""
    from accelcal import bias_lls
    from accelcal.simulation import random_directions, simulate_poses

    rng = np.random.default_rng(1)
    z = simulate_poses(random_directions(rng, 12), 9.8, np.eye(3), np.full(3, 0.01), 1e-4, rng)
    d = bias_lls(z, 9.8).to_dict()
    assert d["lam"] is None
    json.dumps(d, allow_nan=False)
