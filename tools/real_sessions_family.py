"""The loop's decisions on the measured sessions under each wander family, side by side.

Usage: python tools/real_sessions_family.py [family ...]   (default: flicker sum)
Prints per recording and family: the named set, the wander member and the notes of the
sum family's short part (from the rests), from ``../shared/data``.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import yaml

from accelcal.discrepancy.detect import discrepancy
from accelcal.discrepancy.fit import pose_data_from_static
from accelcal.discrepancy.rules import Rules
from accelcal.discrepancy.wander.sums import fit_short
from accelcal.static import detect_static_recording
from accelcal_repro.discrepancy.oracle import named_set
from accelcal_repro.discrepancy.sessions import with_disjoint_rests
from accelcal_repro.measured.sources import fetch_source, read_source


def main(families):
    cfg = yaml.safe_load(Path("config/config.yaml").read_text())
    rules = Rules.from_config(cfg["discrepancy"]["rules"])
    for name in cfg["discrepancy"]["recordings"]:
        g = float(cfg["measured"]["recordings"][name]["g"]) if name in cfg["measured"].get("recordings", {}) else 9.80665
        rec, _ = with_disjoint_rests(read_source(name, fetch_source(name, data_dir="../shared/data")))
        data = pose_data_from_static(detect_static_recording(rec), g, rec.acc, rec.rate)
        short = fit_short(data.rests.full if data.rests is not None else None)
        print(f"{name:18s} rests' short part: {short.describe() if short else 'none'}", flush=True)
        for fam in families:
            res = discrepancy(data, dataclasses.replace(rules, wander_family=fam), report=False)
            print(f"{name:18s} {fam:8s} n={len(data):3d} named={named_set(res.effects, [o.pose for o in res.outliers]) or 'none'}",
                  flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or ["flicker", "sum"])
