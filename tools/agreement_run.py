"""The loop beside the oracle per noise profile, for one or more wander families (issue 34, item 2).

A reduced benchmark (the parametric profiles of config/config.yaml; the fitted and real-record
profiles need the workflow's fitted reports and the ADIS record): ``--none`` effect-free
recordings and ``--seeds`` per (effect, size) and per outlier size, each recording simulated
once and run through the loop under every family of ``--families`` and through the oracle.
Writes ``OUT/key.csv``, ``OUT/detections.csv`` and prints, per (family, profile): agreement
with the oracle, the family-wise false-positive rate with its exact 95 % interval and the
number of effect-free recordings, and detection rates at each size (loop and oracle).

Usage: python tools/agreement_run.py OUT [--families flicker sum] [--profiles ...] [--none 40]
       [--seeds 4] [--sizes 0.5 1 3] [--jobs 2]
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from accelcal.discrepancy.rules import Rules
from accelcal_repro.discrepancy.benchmark import Session, detect_nulls, plan, simulate_case
from accelcal_repro.discrepancy.oracle import oracle_detection
from accelcal_repro.discrepancy.profiles import build_profiles
from accelcal_repro.discrepancy.scoring import clopper_pearson, score_cases
from accelcal_repro.montecarlo import grid_seed

PARAMETRIC = ["white", "rounding", "gm_0.3x_session", "gm_1x_3s", "gm_1x_30s", "gm_3x_session", "gm_mix",
              "flicker_1x", "random_walk_1x", "placement_3x"]


@functools.lru_cache(maxsize=4)
def _setup(profiles):
    cfg = yaml.safe_load(Path("config/config.yaml").read_text())["discrepancy"]
    bench = cfg["benchmark"]
    session = Session.from_config(bench["session"])
    rules = Rules.from_config(cfg["rules"])
    profs = build_profiles([p for p in bench["profiles"] if p["name"] in profiles], session)
    return cfg, session, rules, profs


def _one(args):
    spec, families, profiles = args
    profiles = tuple(profiles)
    cfg, session, rules, profs = _setup(profiles)
    prof = profs[spec["profile"]]
    rec, key = simulate_case(spec["truth"], spec["size_mde"], spec["replicate"], seed=cfg["seed"], session=session,
                             rules=rules, profile=prof)
    orng = np.random.default_rng(grid_seed(cfg["seed"], f"discrepancy-oracle/{spec['profile']}/{spec['truth']}",
                                           float(spec["size_mde"]), int(spec["replicate"])))
    rows = []
    for k, fam in enumerate(families):
        r = dataclasses.replace(rules, wander_family=fam)
        oracle = ((lambda data, rws: oracle_detection(data, prof, session.rate, r, orng, rws)) if k == 0 else None)
        for row in detect_nulls(rec, session.g, r, ("wander",), oracle):
            row["null"] = row["null"] if row["null"] == "oracle" else f"wander_{fam}"
            rows.append({"recording": spec["recording"], **row})
    return {"recording": spec["recording"], **key}, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--families", nargs="+", default=["flicker"])
    ap.add_argument("--profiles", nargs="+", default=PARAMETRIC)
    ap.add_argument("--none", type=int, default=40)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--sizes", nargs="+", type=float, default=[0.5, 1.0, 3.0])
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    _, _, rules, _ = _setup(tuple(a.profiles))
    todo = plan(a.profiles, rules.candidates, a.sizes, a.seeds, a.none, 0, outlier=True)
    specs = [(r._asdict() if hasattr(r, "_asdict") else dict(r), a.families, a.profiles)
             for r in todo.drop(columns=[]).to_dict("records")]
    with ProcessPoolExecutor(a.jobs) as ex:
        res = list(ex.map(_one, specs, chunksize=4))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    key = pd.DataFrame([k for k, _ in res])
    det = pd.DataFrame([r for _, rows in res for r in rows])
    key.to_csv(out / "key.csv", index=False)
    det.to_csv(out / "detections.csv", index=False)
    report(key, det)


def report(key, det):
    sc = score_cases(key.assign(noise_window=-1), det)
    rows = []
    for (null, prof), d in sc.groupby(["null", "profile"], sort=False):
        none = d[d.truth == "none"]
        k, n = int(none["named"].sum()), len(none)
        lo, hi = clopper_pearson(k, n)
        row = {"null": null, "profile": prof, "agreement": d["agrees_with_oracle"].mean() if null != "oracle" else np.nan,
               "fpr": k / n, "fpr_lo": float(lo), "fpr_hi": float(hi), "n_none": n}
        eff = d[~d.truth.isin(["none", "outlier_pose"])]
        for s, g in eff.groupby("size_mde"):
            row[f"power_{s:g}x"] = g["detected"].mean()
            row[f"bias_drift_{s:g}x"] = g.loc[g.truth == "bias_drift", "detected"].mean()
        for s, g in d[d.truth == "outlier_pose"].groupby("size_mde"):
            row[f"outlier_{s:g}x"] = g["outlier_located"].mean()
        rows.append(row)
    tab = pd.DataFrame(rows)
    with pd.option_context("display.width", 250, "display.max_columns", 40, "display.precision", 3):
        print(tab.sort_values(["profile", "null"]).to_string(index=False))
    return tab


if __name__ == "__main__":
    main()
