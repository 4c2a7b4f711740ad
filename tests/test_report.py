"""The reproduction report (accelcal_repro.report, workflow/scripts/report.py): built from a small
fake results tree; every figure id appears, verdicts are colour-coded, rebuilding gives the
same bytes, and broken inputs give one-line errors."""

import re
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from accelcal_repro.claims import COLUMNS, NOT_TESTABLE  # noqa: E402
from accelcal.plotting import save_figure  # noqa: E402
from accelcal_repro.report import (  # noqa: E402
    VERDICT_COLOURS,
    ReportError,
    build_report,
    figure_section,
    load_conclusions,
    parse_lock,
    read_benchmarks,
    read_claims,
    stage_times,
    write_report,
)

REPO = Path(__file__).resolve().parents[1]
FIGURE_IDS = ["burkhard2024_fig1a", "batista2011_fig4", "tereshkov_fig3", "bias_convergence_comparison",
              "measured_calibration", "discrepancy_overview", "zz_unregistered"]
BENCH = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


VERDICTS_SHOWN = ("reproduced", "not_reproduced", "not_reproducible", NOT_TESTABLE)


def _claims(path, verdicts=VERDICTS_SHOWN):
    rows = []
    for i, v in enumerate(verdicts):
        rows.append({"paper": ["burkhard2024", "batista2011", "tereshkov"][i % 3], "claim_id": f"claim_{i}",
                     "claim": f"claim text {i} <b>not markup</b>", "paper_value": "≈35×",
                     "reproduced_value": "" if v == "not_reproducible" else f"{i + 1.5:.1f}",
                     "verdict": v, "evidence": f"results/x_{i}.csv"
                     + (": not testable at this scale: n 1 (runs), needs n >= 3" if v == NOT_TESTABLE else "")})
    pd.DataFrame(rows, columns=list(COLUMNS)).to_csv(path, index=False)


@pytest.fixture
def tree(tmp_path):
    """A fake results tree: PNGs, claims.csv, benchmark TSVs, a summary table."""
    res = tmp_path / "results"
    (res / "figures").mkdir(parents=True)
    for k, fid in enumerate(FIGURE_IDS):
        fig, ax = plt.subplots(figsize=(4, 2.5))
        ax.plot([0, 1, 2], [0, k, k * k], label=fid)
        ax.legend()
        save_figure(fig, res / "figures" / fid)
        plt.close(fig)
    _claims(res / "claims.csv")
    for job, s, rss in [("batista2011/calibration_mc", 3.5, 150.0), ("batista2011/claims", 1.25, 90.5),
                        ("measured/fetch_xsens_mti", 0.5, "-"), ("claims", 2.0, 80.0)]:
        f = res / "benchmarks" / f"{job}.tsv"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(BENCH + f"{s}\t0:00:0{int(s)}\t{rss}\t1\t1\t1\t0\t0\t50\t1\n")
    (res / "measured").mkdir()
    pd.DataFrame({"recording": ["xsens_mti"], "chi2": [256.1]}).to_csv(res / "measured" / "summary.csv", index=False)
    captions = {"burkhard2024_fig1a": 'Bias error, {{ snakemake.config["burkhard2024"]["trials"] }} trials; '
                                   "table ``results/foundation/crlb_summary.csv``.\n\nSecond paragraph.",
                "tereshkov_fig3": "Gyro bias estimates."}
    conclusions = {"burkhard2024_fig1a": "Full LLS is as accurate as full NLLS.",
                   "batista2011_fig4": "The gravity estimate follows the truth."}
    config = {"seed": 123, "burkhard2024": {"trials": 77}, "tereshkov": {"seed": 456, "k": [1, 2]}}
    kwargs = dict(
        claims=res / "claims.csv",
        figures={fid: res / "figures" / f"{fid}.png" for fid in FIGURE_IDS},
        captions=captions, conclusions=conclusions,
        tables=[("measured", "Fit quality", res / "measured" / "summary.csv"),
                ("discrepancy", "Discrepancy summary", res / "discrepancy" / "summary.csv")],
        config=config, lock_text=(REPO / "environment.lock").read_text(),
        benchmarks_dir=res / "benchmarks", config_files=["config/config.yaml", "config/ci.yaml"],
    )
    return tmp_path, kwargs


def test_report_has_every_figure_conclusion_caption_and_table(tree):
    _, kw = tree
    page = build_report(**kw)
    for fid in FIGURE_IDS:
        assert f'id="fig-{fid}"' in page and f'alt="{fid}" src="data:image/png;base64,' in page, fid
    # each figure in its paper's section, the unregistered one in "Other figures"
    order = [page.index(f'id="{key}"') for key in ("burkhard2024", "batista2011", "tereshkov", "measured",
                                                     "discrepancy", "other")]
    assert order == sorted(order)
    assert order[0] < page.index('id="fig-burkhard2024_fig1a"') < order[1] < page.index('id="fig-batista2011_fig4"')
    assert order[2] < page.index('id="fig-bias_convergence_comparison"') < order[3]
    assert page.index('id="fig-zz_unregistered"') > order[5]
    # conclusion beside the figure; caption rendered with the config (Jinja2) and rst code
    assert '<p class="conclusion">Full LLS is as accurate as full NLLS.</p>' in page
    assert "Bias error, 77 trials" in page and "<code>results/foundation/crlb_summary.csv</code>" in page
    assert "<p>Second paragraph.</p>" in page
    # a figure with neither shows just its id; no conclusion invented
    fig = page[page.index('id="fig-measured_calibration"'):]
    assert fig.index('class="fid"') < fig.index("</div></div>") and 'class="conclusion"' not in fig[:fig.index("</div></div>")]
    # tables: the present one rendered, the missing one noted
    assert "<td>xsens_mti</td>" in page and "256.1" in page
    assert "not present (the stage has not run)" in page
    # seeds listed and highlighted in the YAML
    assert "<td>tereshkov.seed</td>" in page and "<mark>seed: 123</mark>" in page
    assert "<mark>  seed: 456</mark>" in page
    # package versions from the lock, wall time per stage
    assert "<td>snakemake-executor-plugin-slurm</td>" in page
    assert re.search(r"<td>batista2011</td><td class=\"num\">2</td><td class=\"num\">4\.75</td>"
                     r"<td class=\"num\">2</td><td class=\"num\">150</td>", page)  # jobs, wall, CPU, memory
    # text from the inputs is escaped, not markup
    assert "<b>not markup</b>" not in page and "&lt;b&gt;not markup&lt;/b&gt;" in page


def test_report_colour_codes_every_verdict(tree):
    _, kw = tree
    page = build_report(**kw)
    for i, verdict in enumerate(VERDICTS_SHOWN):
        bg, fg = VERDICT_COLOURS[verdict]
        row = page[page.index(f'id="claim-claim_{i}"'):]
        row = row[:row.index("</tr>")]
        assert f'class="verdict verdict-{verdict}" style="background:{bg};color:{fg}">{verdict}<' in row
        assert f"results/x_{i}.csv" in row and "≈35×" in row
    def rgb(hex_colour):
        return [int(hex_colour[i:i + 2], 16) for i in (1, 3, 5)]

    r, g, b = rgb(VERDICT_COLOURS["reproduced"][0])
    assert g > r and g > b, "reproduced is not green"
    r, g, b = rgb(VERDICT_COLOURS["not_reproduced"][0])
    assert r > g and r > b, "not_reproduced is not red"
    r, g, b = rgb(VERDICT_COLOURS["not_reproducible"][0])
    assert r == g == b, "not_reproducible is not grey"
    r, g, b = rgb(VERDICT_COLOURS[NOT_TESTABLE][0])
    assert r > g > b and r - b > 40, f"{NOT_TESTABLE} is not amber"


def test_report_counts_not_testable_apart_from_reproduced(tree):
    """A claim the run's scale cannot decide is counted under its own verdict, not as reproduced."""
    _, kw = tree
    page = build_report(**kw)
    assert f"4 claims, 1 reproduced, 1 not_reproduced, 1 {NOT_TESTABLE}, 1 not_reproducible." in page
    head = page[page.index("<table><tr><th>paper</th>"):]
    head = head[:head.index("</tr>")]
    assert head.index(">not_reproduced<") < head.index(f">{NOT_TESTABLE}<") < head.index(">not_reproducible<")
    # tereshkov holds claim_2 (not_reproducible) only; batista2011 claim_1 (not_reproduced);
    # burkhard2024 claim_0 (reproduced) and claim_3 (not testable)
    row = page[page.index('<a href="#claims-burkhard2024">'):]
    row = row[:row.index("</tr>")]
    assert [int(v) for v in re.findall(r'class="num">(\d+)<', row)] == [1, 0, 1, 0]
    assert "the n it has and the n it needs" in page


def test_report_is_self_contained_and_byte_identical(tree):
    tmp, kw = tree
    a = write_report(build_report(**kw), tmp / "a" / "report.html").read_bytes()
    b = write_report(build_report(**kw), tmp / "b" / "report.html").read_bytes()
    assert a == b
    text = a.decode()
    assert not re.search(r"(src|href)=\"(https?:)?//", text), "external resource"
    assert "<script" not in text and "<link" not in text
    assert len(a) < 5e6
    assert not list((tmp / "a").glob(".*tmp")), "temporary file left behind"


def test_missing_or_broken_claims_give_one_line_errors(tree):
    tmp, kw = tree
    with pytest.raises(ReportError, match=r"claims ledger not found: .*claims_gone\.csv") as e:
        build_report(**{**kw, "claims": tmp / "claims_gone.csv"})
    assert "\n" not in str(e.value)
    bad = tmp / "bad.csv"
    _claims(bad, verdicts=("reproduced", "sort_of"))
    with pytest.raises(ReportError, match="unknown verdict"):
        read_claims(bad)
    pd.DataFrame({"paper": ["x"]}).to_csv(bad, index=False)
    with pytest.raises(ReportError, match="lacks column"):
        read_claims(bad)


def test_script_reports_a_missing_claims_file_in_one_line(tmp_path):
    proc = subprocess.run([sys.executable, str(REPO / "workflow" / "scripts" / "report.py")], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "claims ledger not found: results/claims.csv" in lines[0], proc.stderr
    assert not (tmp_path / "results" / "report.html").exists()


def test_benchmarks_are_grouped_by_stage(tree):
    tmp, kw = tree
    bench = read_benchmarks(kw["benchmarks_dir"])
    assert sorted(bench["job"]) == ["batista2011/calibration_mc", "batista2011/claims", "claims",
                                    "measured/fetch_xsens_mti"]
    per_stage = stage_times(bench).set_index("stage")
    assert per_stage.loc["batista2011", "s"] == pytest.approx(4.75)
    assert per_stage.loc["batista2011", "cpu_s"] == pytest.approx(2.0)  # cpu_time 1 s per job
    assert per_stage.loc["batista2011", "max_rss"] == pytest.approx(150.0)
    assert per_stage.loc["batista2011", "jobs"] == 2
    assert per_stage.loc["claims", "s"] == pytest.approx(2.0)
    assert pd.isna(per_stage.loc["measured", "max_rss"])  # "-": not measured, not zero
    assert read_benchmarks(tmp / "nowhere").empty
    (kw["benchmarks_dir"] / "broken.tsv").write_text("wall\n1\n")
    with pytest.raises(ReportError, match="no column 's'"):
        read_benchmarks(kw["benchmarks_dir"])


def test_conclusions_file_covers_known_figures_with_one_line_each(tmp_path):
    conclusions = load_conclusions(REPO / "workflow" / "report" / "conclusions.yaml")
    for fid in ("burkhard2024_fig1a", "batista2011_fig5", "tereshkov_fig4", "tereshkov_installation"):
        assert fid in conclusions
    for fid, text in conclusions.items():
        assert figure_section(fid) != "other", f"{fid} belongs to no section"
        assert 20 < len(text) < 300, fid
    bad = tmp_path / "c.yaml"
    bad.write_text("burkhard2024_fig1a: |\n  two\n  lines\n")
    with pytest.raises(ReportError, match="one non-empty line"):
        load_conclusions(bad)


def test_lock_parsing():
    pins = dict((n, v) for n, v, _ in parse_lock((REPO / "environment.lock").read_text()))
    assert "snakemake" in pins and "snakemake-executor-plugin-slurm" in pins
    assert parse_lock("numpy==2.4.6 ; python_full_version < '3.12' \\\n    --hash=sha256:00\n") == [
        ("numpy", "2.4.6", "python_full_version < '3.12'")]
