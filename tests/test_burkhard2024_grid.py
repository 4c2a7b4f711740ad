"""Experiments of the Burkhard stage merged into one Monte Carlo job per grid point."""

from pathlib import Path

import pandas as pd
import pytest

from accelcal_repro.burkhard2024.grid import EXPERIMENTS, Experiment, experiments_from_config, grid_points, point_key, select

from tests.configs import load_config

REPO = Path(__file__).resolve().parents[1]


def exp(name, data_model="full", n=(24,), s=(1e-4,), g=(0.0,), methods=("full_lls", "bias_lls")):
    return Experiment(name, data_model, tuple(n), tuple(s), tuple(g), tuple(methods))


def test_shared_points_run_once_with_the_union_of_cases():
    exps = {"a": exp("a", s=(1e-5, 1e-4)),
            "b": exp("b", n=(4, 24), methods=("full_lls", "full_nlls", "bias_nlls")),
            "c": exp("c", "bias", g=(0.0, 1e-3), methods=("bias_lls",))}
    pts = grid_points(exps)
    assert list(pts) == ["n4_s0.0001_g0", "n24_s1e-05_g0", "n24_s0.0001_g0", "n24_s0.0001_g0.001"]
    # 4 poses: below the full model's minimum of 10, only the bias-only method runs
    assert pts["n4_s0.0001_g0"]["cases"] == [["full", 0.0, ["bias_nlls"]]]
    assert pts["n24_s0.0001_g0"]["cases"] == [["full", 0.0, ["full_lls", "full_nlls", "bias_lls", "bias_nlls"]],
                                              ["bias", 0.0, ["bias_lls"]]]
    assert pts["n24_s0.0001_g0.001"]["cases"] == [["bias", 1e-3, ["bias_lls"]]]
    assert point_key(100, 3e-2) == "n100_s0.03_g0" and point_key(24, 1e-7, 0.1) == "n24_s1e-07_g0.1"


def test_bad_experiments_are_rejected():
    with pytest.raises(ValueError, match="data_model"):
        exp("x", data_model="sphere")
    with pytest.raises(ValueError, match="unknown method"):
        exp("x", methods=("magic",))
    with pytest.raises(ValueError, match="more poses"):
        exp("x", n=(4, 6), methods=("full_lls", "bias_lls"))


@pytest.mark.parametrize("config", ["config.yaml", "ci.yaml"])
def test_config_experiments_and_the_default_size(config):
    cfg = load_config(config)["burkhard2024"]
    exps = experiments_from_config(cfg["experiments"])
    assert tuple(exps) == EXPERIMENTS
    pts = grid_points(exps)
    if config == "config.yaml":  # the floor: at least 1000 Monte Carlo runs per grid point
        assert cfg["trials"] >= 1000
        assert min(exps["fig1b"].n_poses) == 4 and max(exps["fig1b"].n_poses) >= 100
        assert exps["fig1a"].noise_std[0] == 1e-7 and exps["fig1a"].noise_std[-1] == 1e-3
    # Fig. 1(a), 1(b), 1(c) share the 24-pose point at the noise of 1(b)-(e)
    shared = pts[point_key(24, exps["fig1b"].noise_std[0])]["cases"]
    assert {dm for dm, _, _ in shared} == {"full", "bias"}
    table = pd.DataFrame([{"data_model": dm, "n_poses": p["n_poses"], "noise_std": p["noise_std"], "g_error": g,
                           "method": m} for p in pts.values() for dm, g, ms in p["cases"] for m in ms])
    for e in exps.values():  # every experiment finds all its rows back
        got = select(table, e)
        want = sum(1 for n in e.n_poses for m in e.methods if n >= (10 if m.startswith("full") else 4))
        assert len(got) == want * len(e.noise_std) * len(e.g_error), e.name
