"""Experiments of the Burkhard stage merged into one Monte Carlo job per grid point."""

import dataclasses
import json
import sys
from pathlib import Path

import pandas as pd
import pytest

from accelcal.registry import TABLE_PATH, entry_from_table, estimators
from accelcal_repro.burkhard2024.grid import EXPERIMENTS, Experiment, experiments_from_config, select
from accelcal_repro.montecarlo import DATA_MODELS, METHODS

from tests.configs import load_config

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "workflow" / "scripts"))
import _burkhard2024_points as points  # noqa: E402  (the workflow's split of the grid into jobs)
from _burkhard2024_points import grid_points, point_key  # noqa: E402
from _registry_table import ESTIMATOR_TABLE, accelerometer_estimators  # noqa: E402


def exp(name, data_model="full", n=(24,), s=(1e-4,), g=(0.0,), methods=("full_lls", "bias_lls")):
    """An experiment as the config gives it (checked by Experiment, as the jobs check it)."""
    e = Experiment(name, data_model, tuple(n), tuple(s), tuple(g), tuple(methods))
    return {k: v for k, v in dataclasses.asdict(e).items() if k != "name"}


def test_the_workflow_reads_the_registrys_own_table(tmp_path):
    """The parse-time split reads src/accelcal/estimators.json, the file the registry is built
    from: the same methods in the same order, the same minima and data models; and a row
    changed in the file changes both readers alike (one source, no copy)."""
    assert ESTIMATOR_TABLE.resolve() == TABLE_PATH.resolve()
    assert points.FEWEST == {e.name: e.min_poses for e in estimators("accelerometer")}
    assert list(points.FEWEST) == list(METHODS) and points.DATA_MODELS == DATA_MODELS
    table = json.loads(TABLE_PATH.read_text(encoding="utf-8"))
    for row in table["estimators"]:
        row["min_poses"] += 3
    (tmp_path / "estimators.json").write_text(json.dumps(table), encoding="utf-8")
    read = accelerometer_estimators(tmp_path / "estimators.json")
    assert read == {r["name"]: {"model": r["model"], "fewest": entry_from_table(r).min_poses}
                    for r in table["estimators"] if r["sensor"] == "accelerometer"}
    assert read["full_lls"]["fewest"] == 13 and read["bias_lls"]["fewest"] == 7
    row = dict(table["estimators"][0], min_poses=8)  # 8 poses give 8 equations for the 9 unknowns
    with pytest.raises(ValueError, match="min_poses too small"):
        entry_from_table(row)


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
    pts = grid_points(cfg["experiments"])
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
