"""Rate, jitter, drift, gaps and dropped gyro motions of every real session, timed by the stamps
as written (``--clock stamps``: how accelcal read them before it fitted the sensor's clock) and by
the clock (the default), side by side; and the accelerometer-gyro offset of the sessions whose
gyro is a file of its own.

Reads ``../shared/data`` (the sessions of ``accelcal_repro.gyro.sessions`` and the other
recordings there that a reader takes), calibrates the gyro sessions as ``accelcal calibrate``
does (the bias-only accelerometer where a session has too few poses for the full model) and
prints a Markdown table; ``--out`` writes the numbers as JSON.

Usage::

    .venv/bin/python tools/clock_sessions.py [--out results/clock_sessions.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import warnings

from accelcal.formats import read
from accelcal.gyro.rests import sample_interval
from accelcal_repro.gyro.sessions import DATA, SESSIONS, calibrate_session, local_paths

D = DATA
OTHERS = {
    "fork_data1_bag": (D / "imutk_fork_sessions/data1/rosbag2_2023_08_11-21_37_35", {}),
    "fastahrs_1": (D / "fastahrs_fxos8700/data_sample.csv", {}),
    "fastahrs_2": (D / "fastahrs_fxos8700/data_sample2.csv", {}),
    "px4_sample": (D / "px4_ulog/sample.ulg", {}),
    "px4_small": (D / "px4_ulog/sample_log_small.ulg", {}),
    "ck_acc": (D / "mag_ck_explorer/acc_log.csv", {"rate": 100.0}),
}


def _reading(rec) -> dict:
    tb = sample_interval(rec.t)
    clock = next((n for n in rec.notes if n.startswith("clock:")), "")
    jitter = re.search(r"jitter ([0-9.e+-]+) ms", clock)
    drift = re.search(r"drift ([+-][0-9.e+-]+) ppm", clock)
    return {"rate_hz": rec.rate, "gaps": int(len(tb.gaps)), "jitter_ms": float(jitter.group(1)) if jitter else None,
            "drift_ppm": float(drift.group(1)) if drift else None,
            "offset": next((n for n in rec.notes if "time offset" in n), "")}


def _gyro(spec, paths) -> dict:
    try:
        res = calibrate_session(spec, paths)
    except Exception:  # too few poses for the full accelerometer model
        res = calibrate_session(dataclasses.replace(spec, method="bias_lls"), paths)
    q = res["gyro"].quality
    dropped = re.search(r"(\d+) motions left out: samples are missing", " ".join(q.warnings))
    return {"motions": q.n_motions, "dropped_missing": int(dropped.group(1)) if dropped else 0,
            "chi2_per_dof": q.chi2 / max(q.dof, 1)}


def measure() -> dict:
    names = [n for n in SESSIONS if n != "imucal_annotated"]  # its raw counts take no bias-only accelerometer
    paths = local_paths(names)
    out = {}
    for name in names:
        spec = SESSIONS[name]
        for clock in ("stamps", "auto"):
            s = dataclasses.replace(spec, read={**spec.read, "clock": clock})
            row = {**_reading(read(paths[s.dataset][s.acc], gyro=paths[s.dataset][s.gyro] if s.gyro else None,
                                   intervals=paths[s.dataset][s.intervals] if s.intervals else None, **s.read)),
                   **_gyro(s, paths)}
            out.setdefault(name, {})[clock] = row
    for name, (path, kw) in OTHERS.items():
        for clock in ("stamps", "auto"):
            out.setdefault(name, {})[clock] = _reading(read(path, clock=clock, **kw))
    return out


def table(out: dict) -> str:
    rows = ["| session | rate stamps / clock [Hz] | jitter [ms] | drift [ppm] | gaps | motions | dropped |",
            "|---|---|---|---|---|---|---|"]
    for name, r in out.items():
        a, b = r["stamps"], r["auto"]
        rows.append(f"| {name} | {a['rate_hz']:.4f} / {b['rate_hz']:.4f} | {b['jitter_ms']} | {b['drift_ppm']} | "
                    f"{a['gaps']} / {b['gaps']} | {a.get('motions', '-')} / {b.get('motions', '-')} | "
                    f"{a.get('dropped_missing', '-')} / {b.get('dropped_missing', '-')} |")
    rows += [f"- {name}: {r['auto']['offset']}" for name, r in out.items() if r["auto"]["offset"]]
    return "\n".join(rows)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", help="write the numbers as JSON")
    args = p.parse_args()
    warnings.filterwarnings("ignore")
    out = measure()
    print(table(out))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
