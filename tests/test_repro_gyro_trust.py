"""The gyro figure of merit marks a poorly determined calibration (its trust verdict) and leaves a
well-determined one unmarked, with a legend that says why."""

import matplotlib
import pandas as pd

from accelcal_repro.gyro import report

matplotlib.use("Agg")


def _row(session, calibration, rms, verdict="", reasons=""):
    return {"session": session, "calibration": calibration, "bias": "own_bias", "rms_deg": rms,
            "noise_rms_deg": 0.1, "verdict": verdict, "reasons": reasons}


def test_the_figure_hatches_the_poorly_determined_bar_only_and_says_why():
    fom = pd.DataFrame([_row("good", "accelcal", 0.12, "trusted"), _row("good", "factory", 1.2),
                        _row("misfit", "accelcal", 0.4, "caution", "excess 15.1"),
                        _row("weak", "accelcal", 8.3, "poorly_determined", "3 dof; scale x/y/z ± 13/4.1/8.5 %")])
    fig = report.figure(fom)
    ax = fig.axes[0]
    bars = [p for p in ax.patches if p.get_height() > 0]
    hatched = [round(p.get_height(), 2) for p in bars if p.get_hatch()]
    assert hatched == [8.3]  # the poorly determined one; not the trusted nor the merely misfitting one
    texts = [t.get_text() for t in ax.texts]
    assert texts == ["3 dof\nscale x/y/z ± 13/4.1/8.5 %"]
    assert any("poorly determined" in t.get_text() for t in ax.get_legend().get_texts())
    unmarked = report.figure(fom[fom.session != "weak"]).axes[0]
    assert not any(p.get_hatch() for p in unmarked.patches) and not unmarked.texts
    assert not any("poorly" in t.get_text() for t in unmarked.get_legend().get_texts())
