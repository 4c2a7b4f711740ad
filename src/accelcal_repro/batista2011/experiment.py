"""Build the Batista (2011) experiments from the workflow config (``config["batista2011"]``).

Pure functions of the config mapping (section ``batista2011`` of ``config/config.yaml``), so that
the workflow scripts stay thin and the tests can build the same experiments.
"""

from __future__ import annotations

import numpy as np

from .montecarlo import CalibrationDesign, FilterScenario, calibration_design, filter_scenario
from .trajectory import Attitude, constant_axis_attitude, euler_sinusoid_attitude


def design_from_config(cfg: dict) -> CalibrationDesign:
    """The calibration experiment of ``cfg`` (the ``batista2011`` mapping)."""
    c = cfg["calibration"]
    att = c["attitudes"]
    tr = c["truth"]
    return calibration_design(att["roll_deg"], att["pitch_deg"], att["yaw_deg"], c["mounting_offset_deg"],
                              cfg["g"], np.array(tr["F_inv"], float), tr["b_prime"], tr["f2"], c["noise_std"],
                              **{k: float(v) for k, v in c["schedule"].items()})


def filter_times(cfg: dict) -> np.ndarray:
    f = cfg["filter"]
    rate = float(f["rate"])
    return np.arange(int(round(float(f["duration_s"]) * rate)) + 1) / rate


def changing_attitude(cfg: dict, t=None) -> Attitude:
    """The filter trajectory (direction of ω changes)."""
    a = cfg["filter"]["attitude"]
    return euler_sinusoid_attitude(filter_times(cfg) if t is None else t, a["offset_deg"], a["amplitude_deg"],
                                   a["frequency_hz"], a["phase_deg"], a["rate_deg_s"])


def constant_attitude(cfg: dict, t=None) -> Attitude:
    """The fixed-axis trajectory of the observability experiment."""
    o = cfg["observability"]
    return constant_axis_attitude(filter_times(cfg) if t is None else t, o["axis_body"], o["base_euler_deg"],
                                  o["mean_rate_deg_s"], o["amplitude_deg"], o["frequency_hz"])


def scenario_from_config(cfg: dict, case: str = "changing") -> FilterScenario:
    """Filter truth on the ``changing`` (default) or ``constant`` axis trajectory."""
    f = cfg["filter"]
    att = changing_attitude(cfg) if case == "changing" else constant_attitude(cfg)
    n = f["noise"]
    return filter_scenario(att, f["bias"], n["accel"], n["gyro_deg_s"], n["velocity"], cfg["g"], f["lever_arm_m"])


def p0_diag(cfg: dict) -> np.ndarray:
    """Initial covariance diagonal from ``P0_std`` (v, g, b)."""
    return np.repeat(np.asarray(cfg["filter"]["P0_std"], float) ** 2, 3)


def filter_kwargs(cfg: dict) -> dict:
    f = cfg["filter"]
    return {"P0_diag": p0_diag(cfg), "xi": tuple(float(x) for x in f["xi"]), "theta": float(f["theta"])}


__all__ = ["changing_attitude", "constant_attitude", "design_from_config", "filter_kwargs", "filter_times",
           "p0_diag", "scenario_from_config"]
