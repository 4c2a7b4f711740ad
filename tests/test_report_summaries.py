"""The report shows each result through its Summary's HTML renderer (statsmodels' idea: one
Summary, text for the command line, HTML for the report), and every result type the stages make
that has a Summary reaches the report that way (a census over the workflow's scripts)."""

import ast
import re
from pathlib import Path

import pytest

from accelcal.summary import Summary, read_summaries, write_summaries
from accelcal_repro.report import FIGURE_SECTIONS, ReportError, build_report, summaries_html
from tests.test_report import tree  # noqa: F401  (the fake results tree of the report's tests, a fixture)

REPO = Path(__file__).resolve().parents[1]
SCRIPTS = REPO / "workflow" / "scripts"
RULES = REPO / "workflow" / "rules"

#: Result type with a Summary -> the stage script that makes it for the report.  A new
#: stage that shows such a result adds its line here (the census below checks the script).
SUMMARY_SOURCES = {
    "Calibration": "measured_calibrate.py",
    "DiscrepancyReport": "discrepancy_measured.py",
    "NoiseReport": "noise_adis.py",
    "GyroCalibration": "gyro_sessions.py",
    "MagCalibration": "mag_sessions.py",
}


def _summaries(tmp_path):
    a = Summary(["full-lls: 30 poses; data in m/s^2; g = 9.80665 m/s^2", "  scale [ppm]: x +12 ± 3 <1>",
                 "warning: only 3 degree(s) of freedom", "  written to cal.json"])
    b = Summary("bias-lls: 12 poses\n  bias [m/s^2]: x 0.01")
    path = tmp_path / "summaries" / "measured_xsens.json"
    write_summaries(path, {"full_lls": a, "bias_lls": b})
    return path, a, b


def test_summaries_file_keeps_every_summary_whole(tmp_path):
    path, a, b = _summaries(tmp_path)
    back = read_summaries(path)
    assert list(back) == ["full_lls", "bias_lls"] and back["full_lls"] == a and back["bias_lls"] == b
    assert back["full_lls"].warnings == ["only 3 degree(s) of freedom"]
    nested = Summary("magnetometer (ellipsoid_ml)\n  hard iron b = 1 ± 2\n  warning: magnetometer: few directions")
    assert nested.warnings == ["magnetometer: few directions"] and nested.body == ["  hard iron b = 1 ± 2"]
    (tmp_path / "bad.json").write_text('{"tables": []}')
    with pytest.raises(ReportError, match="not a summaries file"):
        summaries_html(tmp_path / "bad.json")


def test_report_sections_render_the_summaries_by_as_html(tree, tmp_path):  # noqa: F811
    """The page holds each Summary's as_html verbatim, in its stage's section, before the tables."""
    path, a, b = _summaries(tmp_path)
    kw = tree[1]
    page = build_report(**kw, summaries=[("measured", "xsens: each estimator's calibration", path),
                                         ("noise", "ADIS16405", tmp_path / "absent.json")])
    for name, s in (("full_lls", a), ("bias_lls", b)):
        assert f'<p class="fid">{name}</p>{s.as_html()}' in page  # under its name in the job
    assert "&lt;1&gt;" in page and "<1>" not in page  # the renderer escapes
    measured = page.index('id="measured"')
    assert measured < page.index(a.as_html()) < page.index("<td>xsens_mti</td>") < page.index('id="discrepancy"')
    # a summaries file the stage has not made yet is noted, as a table is
    noise = page[page.index('id="noise"'):]
    assert "not present (the stage has not run)" in noise[:noise.index("</section>")]
    # and nothing else of the page renders a summary: one renderer
    assert page.count('<section class="summary">') == 2


def _calls(path: Path, name: str) -> int:
    tree = ast.parse(path.read_text())
    return sum(isinstance(n, ast.Call) and getattr(n.func, "id", getattr(n.func, "attr", "")) == name
               for n in ast.walk(tree))


@pytest.mark.parametrize("result, script", sorted(SUMMARY_SOURCES.items()))
def test_every_shown_result_with_a_summary_reaches_the_report(result, script):
    """The census: the script writes its results' summaries, its rule has a ``summaries`` output
    (results/summaries/), and its stage declares them for the report."""
    assert _calls(SCRIPTS / script, "write_summaries") == 1, script
    rule_files = [p for p in RULES.glob("*.smk") if f'"../scripts/{script}"' in p.read_text()]
    assert len(rule_files) == 1, script
    text = rule_files[0].read_text()
    rule = text[:text.index(f'"../scripts/{script}"')].rsplit("\nrule ", 1)[1]
    m = re.search(r"summaries=summaries_path\((f?\"[^\"]+\")\)", rule)
    assert m, f"{script}: no summaries output"
    declared = text[text.index("declare_stage("):]
    assert "summaries=" in declared[:declared.index("\n)\n")], f"{rule_files[0].name}: no summaries declared"


def test_every_summary_type_is_in_the_census():
    """A result type the report shows with a Summary is one the summaries' census names
    (the library's census of types: tests/test_summaries.py); the loops' results are lines of
    the discrepancy report's Summary, DiscrepancyResult is its deterministic layer's."""
    from tests.test_summaries import SRC, classes_with_a_summary

    inside_another = {"DiscrepancyResult", "GyroLoopResult", "MagLoopResult"}
    assert sorted(set(classes_with_a_summary(SRC / "accelcal")) - inside_another) == sorted(SUMMARY_SOURCES)


def test_every_stage_has_a_section_of_the_report():
    """The page shows a stage's tables and summaries in the section named after it: the mag stage had
    none, and its tables were left out of the page; a section-less table now goes to "Other"."""
    stages = set(re.findall(r'declare_stage\(\s*name="(\w+)"', "".join(p.read_text() for p in RULES.glob("*.smk"))))
    assert len(stages) >= 9 and stages <= {key for key, _, _ in FIGURE_SECTIONS}, stages


def test_a_table_of_an_unknown_section_is_shown_not_dropped(tree, tmp_path):  # noqa: F811
    path, a, _ = _summaries(tmp_path)
    page = build_report(**tree[1], summaries=[("no_such_stage", "kept", path)])
    assert page.index('id="other"') < page.index(a.as_html())
