"""The reproduction report: one self-contained HTML page a reviewer opens first.

:func:`build_report` turns the workflow's results into one HTML string: for each paper its
figures, each beside a one-line statement of the paper's conclusion
(``workflow/report/conclusions.yaml``) and its caption; the measured-data and discrepancy
figures, the summaries of the results they show (each rendered by its
:meth:`accelcal.summary.Summary.as_html`, the text the command line prints) and summary
tables; the claims ledger with colour-coded verdicts; the
configuration with the seeds highlighted; the package versions pinned in
``environment.lock``; and the wall time and peak memory of each stage from Snakemake's
benchmark files (``results/benchmarks/<stage>/<job>.tsv``).

The page is self-contained (figures embedded as downscaled base64 PNG, CSS inline, no
external URL) and deterministic: no time stamps, every mapping iterated in sorted order,
so rebuilding it from the same inputs gives the same bytes.  Pure functions, no Snakemake
import; ``workflow/scripts/report.py`` wires them to the rule ``report``.
"""

from __future__ import annotations

import base64
import html
import io
import numbers
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd
import yaml

from accelcal.atomic import atomic_output
from accelcal.summary import read_summaries
from .claims import COLUMNS, NOT_TESTABLE, PAPERS, VERDICTS

#: Sections of the page that hold figures: (key, title, figure-id prefixes), one per stage
#: (the key is the stage's name).  A figure id matching no prefix, or a table of a stage without
#: a section, goes to "Other figures" (shown, never dropped).
FIGURE_SECTIONS = (
    ("burkhard2024", "Burkhard, Sharma, Skaloud (2024): linear estimation of deterministic accelerometer errors",
     ("foundation_", "burkhard2024_")),
    ("batista2011", "Batista, Silvestre, Oliveira, Cardeira (2011): calibration and dynamic bias and gravity estimation",
     ("batista2011_",)),
    ("tereshkov", "Tereshkov: an intuitive approach to inertial sensor bias estimation",
     ("tereshkov_", "bias_convergence_comparison")),
    ("measured", "Measured data: public recordings calibrated without ground truth", ("measured_",)),
    ("discrepancy", "Discrepancy: where simulation and measured data disagree, and the missing effect", ("discrepancy_",)),
    ("gyro", "Gyroscope: calibrated from the same session, one-step vs iterative, and the peers side by side",
     ("gyro_",)),
    ("noise", "Noise: a static record's noise terms against the datasheet, and the intervals' coverage", ("noise_",)),
    ("mag", "Magnetometer: calibrated from the same session, beside the peers", ("mag_",)),
    ("benchmark", "Benchmark: where the compute time goes (estimators, filters, compilation, stages)", ("timing_",)),
)
OTHER_SECTION = ("other", "Other figures")

#: Verdict colours (background, text) of the ledger: green, red, amber (the rule could not be
#: decided at this scale: neither a success nor a failure), grey (nothing to compute it from).
VERDICT_COLOURS = {
    "reproduced": ("#d6f5d6", "#145214"),
    "not_reproduced": ("#f8d4d4", "#7a1010"),
    NOT_TESTABLE: ("#fbe8c4", "#6b4500"),
    "not_reproducible": ("#e4e4e4", "#444444"),
}

#: Width [px] figures wider than this are downscaled to; the figures' own PNGs (150 dpi)
#: are about 1100 px wide, which is what a screen shows.
FIGURE_WIDTH = 1200
#: Colours of the embedded figures: a 256-colour palette keeps the page at about 2 MB
#: (full RGB: about 5 MB) with no visible change to line plots.
FIGURE_COLOURS = 256

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;max-width:1280px;
padding:0 1.5em 3em;color:#222;line-height:1.4}
h1{margin-top:1em}h2{border-bottom:2px solid #ccc;padding-bottom:.2em;margin-top:2em}
nav ul{columns:2;font-size:.95em}
.figure{display:flex;gap:1.2em;align-items:flex-start;margin:1.2em 0;padding:.8em;border:1px solid #ddd;
border-radius:6px}
.figure img{max-width:62%;height:auto;border:1px solid #eee}
.figure .text{flex:1;font-size:.9em}
.conclusion{font-size:1.05em;font-weight:600;margin:0 0 .6em;padding:.4em .6em;background:#eef4fb;
border-left:4px solid #3b78c2}
.fid{font-family:monospace;color:#666;font-size:.85em}
table{border-collapse:collapse;font-size:.85em;margin:.6em 0}
th,td{border:1px solid #ccc;padding:.25em .5em;vertical-align:top;text-align:left}
th{background:#f3f3f3}
td.num{text-align:right;font-variant-numeric:tabular-nums}
.verdict{font-weight:600;white-space:nowrap}
pre{background:#f7f7f7;padding:.8em;overflow-x:auto;font-size:.82em}
mark{background:#ffe57a}
.note{color:#555;font-size:.9em}
.tablewrap{overflow:auto;max-height:40em}
thead th{position:sticky;top:0}
h4{margin:.9em 0 .2em;font-size:.95em}
details summary{cursor:pointer;color:#3b78c2;font-size:.9em;margin:.3em 0}
section.summary{border:1px solid #ddd;border-radius:6px;padding:.2em .8em;margin:.1em 0 .8em;background:#fcfcfc}
section.summary pre{margin:.3em 0;padding:.5em;white-space:pre-wrap}
ul.warnings{color:#6b4500;font-size:.85em;margin:.3em 0;padding-left:1.2em}
"""


class ReportError(ValueError):
    """An input of the report that is missing or malformed (one-line message)."""


# ------------------------------------------------------------------------------ inputs
def figure_section(figure_id: str) -> str:
    """Key of the section a figure belongs to (by its id's prefix)."""
    for key, _, prefixes in FIGURE_SECTIONS:
        if figure_id.startswith(prefixes):
            return key
    return OTHER_SECTION[0]


def read_claims(path: str | os.PathLike) -> pd.DataFrame:
    """The claims ledger (``results/claims.csv``), checked for the ledger's columns."""
    path = Path(path)
    if not path.is_file():
        raise ReportError(f"claims ledger not found: {path} (make it with `snakemake claims`)")
    try:
        ledger = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise ReportError(f"claims ledger {path} is not a readable CSV: {str(e).splitlines()[0]}") from None
    missing = [c for c in COLUMNS if c not in ledger]
    if missing:
        raise ReportError(f"claims ledger {path} lacks column(s) {', '.join(missing)}")
    bad = sorted(set(ledger["verdict"]) - set(VERDICTS))
    if bad:
        raise ReportError(f"claims ledger {path} has unknown verdict(s) {', '.join(bad)} (known: {', '.join(VERDICTS)})")
    return ledger[list(COLUMNS)]


def load_conclusions(path: str | os.PathLike) -> dict[str, str]:
    """Figure id -> one-line statement of the paper's conclusion (a YAML mapping)."""
    path = Path(path)
    if not path.is_file():
        raise ReportError(f"conclusions file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except yaml.YAMLError as e:
        raise ReportError(f"conclusions file {path} is not valid YAML: {str(e).splitlines()[0]}") from None
    if not isinstance(data, dict):
        raise ReportError(f"conclusions file {path} must map figure ids to one-line statements")
    out = {}
    for fid, text in data.items():
        if not isinstance(text, str) or not text.strip() or "\n" in text.strip():
            raise ReportError(f"conclusions file {path}: entry {fid!r} must be one non-empty line")
        out[str(fid)] = " ".join(text.split())
    return out


def render_caption(text: str, config: Mapping) -> str:
    """A figure caption (reStructuredText with Jinja2 expressions over
    ``snakemake.config``, as Snakemake's own report renders it) as HTML paragraphs."""
    try:
        text = jinja2.Template(text, undefined=jinja2.StrictUndefined).render(snakemake={"config": config})
    except jinja2.TemplateError as e:
        raise ReportError(f"caption cannot be rendered: {str(e).splitlines()[0]}") from None
    paragraphs = [" ".join(p.split()) for p in re.split(r"\n\s*\n", text) if p.strip()]
    out = []
    for p in paragraphs:
        p = html.escape(p)
        p = re.sub(r"``(.+?)``", r"<code>\1</code>", p)
        out.append(f"<p>{p}</p>")
    return "\n".join(out)


def embed_png(path: str | os.PathLike, width: int = FIGURE_WIDTH) -> str:
    """A PNG as a ``data:`` URI, downscaled to at most ``width`` pixels and reduced to a
    palette of :data:`FIGURE_COLOURS` colours (fast octree, no dithering: deterministic).

    Fast octree and zlib's default level instead of median cut and ``optimize``: on the
    31 figures of the CI run 1.5 s instead of 5.9 s, and 1.7 MB instead of 2.3 MB (line
    plots have few colours; the two palettes look the same)."""
    from PIL import Image  # matplotlib's own image library

    path = Path(path)
    if not path.is_file():
        raise ReportError(f"figure not found: {path}")
    try:
        with Image.open(path) as im:
            im = im.convert("RGB")
            if im.width > width:
                im = im.resize((width, round(im.height * width / im.width)), Image.LANCZOS)
            im = im.quantize(FIGURE_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
            buf = io.BytesIO()
            im.save(buf, format="PNG")
    except OSError as e:
        raise ReportError(f"figure {path} is not a readable image: {e}") from None
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def read_benchmarks(directory: str | os.PathLike) -> pd.DataFrame:
    """Every Snakemake benchmark file under ``directory`` (``<stage>/<job>.tsv`` or
    ``<stage>.tsv``): one row per job with its stage, wall time ``s`` [s] and CPU time
    ``cpu_s`` [s] (Snakemake's ``cpu_time``; both summed over repeats, NaN if not
    measured) and peak resident memory ``max_rss`` [MB] (max over repeats; NaN if not
    measured).  Empty when there are none."""
    directory = Path(directory)
    rows = []
    for f in sorted(directory.rglob("*.tsv")) if directory.is_dir() else []:
        rel = f.relative_to(directory).with_suffix("").as_posix()
        try:
            t = pd.read_csv(f, sep="\t")
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
            raise ReportError(f"benchmark file {f} is not readable: {str(e).splitlines()[0]}") from None
        if "s" not in t:
            raise ReportError(f"benchmark file {f} has no column 's' (wall time)")
        rss = pd.to_numeric(t["max_rss"], errors="coerce") if "max_rss" in t else pd.Series(dtype=float)
        cpu = pd.to_numeric(t["cpu_time"], errors="coerce") if "cpu_time" in t else pd.Series(dtype=float)
        rows.append({"stage": rel.split("/")[0], "job": rel,
                     "s": float(pd.to_numeric(t["s"], errors="coerce").sum()),
                     "cpu_s": float(cpu.sum()) if cpu.notna().any() else float("nan"),
                     "max_rss": float(rss.max()) if rss.notna().any() else float("nan")})
    return pd.DataFrame(rows, columns=["stage", "job", "s", "cpu_s", "max_rss"])


def stage_times(bench: pd.DataFrame) -> pd.DataFrame:
    """Per stage: number of jobs, summed wall time and CPU time [s], largest peak memory [MB]."""
    if bench.empty:
        return pd.DataFrame(columns=["stage", "jobs", "s", "cpu_s", "max_rss"])
    g = bench.groupby("stage", sort=True)
    return pd.DataFrame({"jobs": g.size(), "s": g["s"].sum(), "cpu_s": g["cpu_s"].sum(min_count=1),
                         "max_rss": g["max_rss"].max()}).reset_index()


_PIN = re.compile(r"^([A-Za-z0-9_.\-]+)==([^\s;\\]+)\s*(?:;\s*([^\\]*?))?\s*\\?\s*$")


def parse_lock(text: str) -> list[tuple[str, str, str]]:
    """``(name, version, environment marker)`` of every ``name==version`` pin of a
    lock file, in the file's order."""
    pins = []
    for line in text.splitlines():
        m = _PIN.match(line)
        if m:
            pins.append((m.group(1), m.group(2), (m.group(3) or "").strip()))
    return pins


def seed_paths(cfg, prefix: str = "") -> list[tuple[str, object]]:
    """``(dotted key, value)`` of every config key whose name contains "seed"."""
    out = []
    if isinstance(cfg, Mapping):
        for k in sorted(cfg, key=str):
            path = f"{prefix}.{k}" if prefix else str(k)
            if "seed" in str(k).lower() and not isinstance(cfg[k], (Mapping, list)):
                out.append((path, cfg[k]))
            out += seed_paths(cfg[k], path)
    elif isinstance(cfg, list):
        for i, v in enumerate(cfg):
            out += seed_paths(v, f"{prefix}[{i}]")
    return out


# ---------------------------------------------------------------------------- HTML bits
def _esc(x) -> str:
    return html.escape(str(x))


def _fmt(x) -> str:
    if isinstance(x, float):
        return "" if x != x else f"{x:.4g}"
    return str(x)


def _rows_html(df: pd.DataFrame) -> str:
    head = "".join(f"<th>{_esc(c)}</th>" for c in df.columns)
    body = []
    for row in df.itertuples(index=False):
        cells = []
        for v in row:
            num = isinstance(v, numbers.Number) and not isinstance(v, (bool, np.bool_))
            cells.append(f'<td class="num">{_esc(_fmt(v))}</td>' if num else f"<td>{_esc(_fmt(v))}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f'<div class="tablewrap"><table><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table></div>'


def html_table(df: pd.DataFrame, max_rows: int = 200) -> str:
    """A data frame as an HTML table (numbers right-aligned, 4 significant digits)."""
    more = f'<p class="note">{len(df) - max_rows} more rows in the file.</p>' if len(df) > max_rows else ""
    return _rows_html(df.head(max_rows)) + more


#: How the report shows its wide or long summary tables: the columns to read first (the
#: others in an "all columns" block), one sub-table per value of ``group``, and at most
#: ``rows`` rows before a "more rows" block.  A table without a view gets the default.
TABLE_VIEWS = {
    "results/measured/summary.csv": {
        "columns": ["estimator", "n_poses", "dof", "residual_rms", "predicted_rms", "excess", "p_value",
                    "lopo_rms", "ci_method", "distinct_orientations", "coverage", "warnings"],
        "group": "recording"},
    "results/measured/nominal.csv": {"group": "recording"},
    "results/discrepancy/summary.csv": {
        "columns": ["recording", "effect", "metric", "value", "ci_low", "ci_high", "n", "target", "verdict"],
        "group": "section"},
    "results/noise/adis16405/datasheet.csv": {
        "columns": ["quantity", "reading", "axis", "fitted", "interval_low", "interval_high", "datasheet",
                    "datasheet_as_written", "unit", "ratio"],
        "group": "sensor"},
    "results/noise/coverage.csv": {
        "columns": ["term", "true", "axes", "coverage", "coverage_low", "coverage_high", "median_relative_width",
                    "resolved_share"],
        "group": "configuration"},
}
TABLE_VIEWS.update({
    "results/gyro/sessions/sessions.csv": {
        "columns": ["session", "estimator", "poses", "motions", "chi2_per_dof", "excess", "residual_rms_deg",
                    "predicted_rms_deg", "time_base", "g_sensitivity", "warnings", "error"]},
    "results/gyro/sessions/figure_of_merit.csv": {"group": "session"},
    "results/gyro/sessions/peer_parameters.csv": {"group": "session", "rows": 45},
    "results/gyro/sessions/stability.csv": {"group": "group", "rows": 12},
    "results/gyro/montecarlo_summary.csv": {"rows": 30},
})
DEFAULT_VIEW = {"max_columns": 12, "rows": 25}


def view_table(df: pd.DataFrame, view: Mapping | None = None) -> str:
    """A summary table made readable: key columns first, groups, long tables folded.

    Parameters
    ----------
    df : DataFrame
    view : mapping, optional
        ``columns`` (shown; default the first ``max_columns``), ``group`` (a column:
        one sub-table per value, in order of appearance), ``rows`` (shown before the rest
        is folded).  Columns the file lacks are skipped, so a table that grows a column
        still renders.
    """
    view = {**DEFAULT_VIEW, **(view or {})}
    group = view.get("group") if view.get("group") in df.columns else None
    wanted = [c for c in view.get("columns", df.columns[: view["max_columns"]]) if c in df.columns and c != group]
    hidden = [c for c in df.columns if c not in wanted and c != group]
    parts = []
    groups = [(None, df)] if group is None else [(k, df[df[group] == k]) for k in dict.fromkeys(df[group])]
    for key, d in groups:
        if key is not None:
            parts.append(f"<h4>{_esc(group)}: {_esc(key if key == key else '')}</h4>")
        shown = d[wanted]
        n = view["rows"]
        parts.append(_rows_html(shown.head(n)))
        if len(shown) > n:
            parts.append(f"<details><summary>{len(shown) - n} more rows</summary>{_rows_html(shown.iloc[n:])}</details>")
    if hidden:
        parts.append(f'<details><summary>all {len(df.columns)} columns ({", ".join(hidden[:8])}'
                     f'{", ..." if len(hidden) > 8 else ""} not shown above)</summary>{_rows_html(df)}</details>')
    return "".join(parts)


def verdict_cell(verdict: str) -> str:
    bg, fg = VERDICT_COLOURS[verdict]
    return f'<td class="verdict verdict-{verdict}" style="background:{bg};color:{fg}">{_esc(verdict)}</td>'


def ledger_html(ledger: pd.DataFrame) -> str:
    """The claims ledger grouped by paper, verdicts colour-coded."""
    parts = ['<table class="ledger"><thead><tr><th>claim</th><th>paper value</th><th>reproduced value</th>'
             "<th>verdict</th><th>evidence</th></tr></thead><tbody>"]
    order = {p: i for i, p in enumerate(PAPERS)}
    for paper in sorted(set(ledger["paper"]), key=lambda p: (order.get(p, len(order)), p)):
        parts.append(f'<tr><th colspan="5" id="claims-{_esc(paper)}">{_esc(paper)}</th></tr>')
        for r in ledger[ledger["paper"] == paper].itertuples(index=False):
            parts.append(f'<tr id="claim-{_esc(r.claim_id)}"><td><span class="fid">{_esc(r.claim_id)}</span><br>'
                         f"{_esc(r.claim)}</td><td>{_esc(r.paper_value)}</td><td>{_esc(r.reproduced_value)}</td>"
                         f"{verdict_cell(r.verdict)}<td>{_esc(r.evidence)}</td></tr>")
    parts.append("</tbody></table>")
    return "".join(parts)


def verdict_summary_html(ledger: pd.DataFrame) -> str:
    counts = ledger.groupby(["paper", "verdict"]).size()
    papers = [p for p in PAPERS if p in set(ledger["paper"])] + sorted(set(ledger["paper"]) - set(PAPERS))
    head = "<tr><th>paper</th>" + "".join(
        f'<th style="background:{VERDICT_COLOURS[v][0]};color:{VERDICT_COLOURS[v][1]}">{v}</th>' for v in VERDICTS
    ) + "</tr>"
    rows = "".join(
        f'<tr><td><a href="#claims-{_esc(p)}">{_esc(p)}</a></td>'
        + "".join(f'<td class="num">{int(counts.get((p, v), 0))}</td>' for v in VERDICTS) + "</tr>"
        for p in papers
    )
    return f"<table>{head}{rows}</table>"


def figure_html(figure_id: str, png_uri: str, conclusion: str | None, caption_html: str) -> str:
    stmt = f'<p class="conclusion">{_esc(conclusion)}</p>' if conclusion else ""
    return (f'<div class="figure" id="fig-{_esc(figure_id)}"><img alt="{_esc(figure_id)}" src="{png_uri}">'
            f'<div class="text">{stmt}<p class="fid">{_esc(figure_id)}</p>{caption_html}</div></div>')


def config_html(config: Mapping) -> str:
    """The config as YAML (sorted keys), lines with a seed highlighted."""
    text = yaml.safe_dump(config, sort_keys=True, default_flow_style=None, allow_unicode=True, width=100)
    lines = []
    for line in text.splitlines():
        esc = _esc(line)
        key = line.strip().split(":", 1)[0]
        lines.append(f"<mark>{esc}</mark>" if "seed" in key.lower() else esc)
    return "<pre>" + "\n".join(lines) + "</pre>"


# ------------------------------------------------------------------------------ report
def build_report(*, claims: str | os.PathLike, figures: Mapping[str, str | os.PathLike],
                 captions: Mapping[str, str], conclusions: Mapping[str, str],
                 tables: Sequence[tuple[str, str, str | os.PathLike]], config: Mapping, lock_text: str,
                 benchmarks_dir: str | os.PathLike, config_files: Sequence[str] = (),
                 summaries: Sequence[tuple[str, str, str | os.PathLike]] = ()) -> str:
    """The report page as one HTML string.

    Parameters
    ----------
    claims
        ``results/claims.csv`` (required: a missing file is a :class:`ReportError`).
    figures
        Figure id -> PNG path.
    captions
        Figure id -> caption text (reStructuredText + Jinja2 over ``snakemake.config``);
        a figure without one shows its conclusion only.
    conclusions
        Figure id -> one-line statement of the paper's conclusion; a figure without one
        shows its caption only.
    tables
        ``(section key, title, CSV path)`` of the summary tables to show (section keys as
        in :data:`FIGURE_SECTIONS`); a path that does not exist is noted, not an error.
    config
        The workflow config (shown as YAML, seeds highlighted).
    lock_text
        The text of ``environment.lock``.
    benchmarks_dir
        ``results/benchmarks``: read as it is when the report is built.
    config_files
        The config files of the run, in the order they were applied.
    summaries
        ``(section key, title, path)`` of the stages' summaries files
        (:func:`accelcal.summary.write_summaries`): each result's Summary rendered by its
        ``as_html``, before the section's tables; a path that does not exist is noted.
    """
    ledger = read_claims(claims)
    nav, body = _figure_sections(ledger, figures, captions, conclusions, [*summaries, *tables], config)
    for key, title, html in (("claims", "Claims ledger", _ledger_section(ledger)),
                             ("config", "Configuration and seeds", _config_section(config, config_files)),
                             ("environment", "Package versions", _environment_section(lock_text)),
                             ("walltime", "Wall time per stage", _walltime_section(benchmarks_dir))):
        nav.append(f'<li><a href="#{key}">{title}</a></li>')
        body.append(html)
    n_by_verdict = ", ".join(f"{int((ledger['verdict'] == v).sum())} {v}" for v in VERDICTS)
    head = ('<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>accelcal reproduction report</title><style>{CSS}</style></head><body>")
    intro = ("<h1>accelcal reproduction report</h1><p>Reproductions of Burkhard, Sharma, Skaloud (2024), "
             "Batista et al. (2011) and Tereshkov from simulations, public recordings calibrated without ground "
             f"truth, and the claims ledger: {len(ledger)} claims, {n_by_verdict}.</p>"
             f"{verdict_summary_html(ledger)}<nav><ul>{''.join(nav)}</ul></nav>")
    return head + intro + "\n".join(body) + "</body></html>\n"


def _figure_sections(ledger, figures, captions, conclusions, tables, config) -> tuple[list[str], list[str]]:
    """The navigation entries and sections of the figures and summary tables, section by section."""
    by_section: dict[str, list[str]] = {}
    for fid in sorted(figures):
        by_section.setdefault(figure_section(fid), []).append(fid)
    sections = [(k, t) for k, t, _ in FIGURE_SECTIONS] + [OTHER_SECTION]
    tables_by_section: dict[str, list[tuple[str, Path]]] = {}
    known = {k for k, _ in sections}
    for key, title, path in tables:  # the summaries first, then the tables; an unknown section's: "Other"
        tables_by_section.setdefault(key if key in known else OTHER_SECTION[0], []).append((title, Path(path)))
    nav, body = [], []
    for key, title in sections:
        figs, tabs = by_section.get(key, []), tables_by_section.get(key, [])
        if not figs and not tabs:
            continue
        nav.append(f'<li><a href="#{key}">{_esc(title)}</a></li>')
        body.append(f'<section><h2 id="{key}">{_esc(title)}</h2>')
        if key in PAPERS:
            n = int((ledger["paper"] == key).sum())
            body.append(f'<p class="note">{n} claim(s) of this paper in the <a href="#claims-{key}">ledger</a>.</p>')
        for fid in figs:
            try:
                caption = render_caption(captions[fid], config) if fid in captions else ""
            except ReportError as e:
                raise ReportError(f"figure {fid}: {e}") from None
            body.append(figure_html(fid, embed_png(figures[fid]), conclusions.get(fid), caption))
        body += [_table_html(title_t, path) for title_t, path in tabs]  # in the order the stages registered them
        body.append("</section>")
    return nav, body


def summaries_html(path: str | os.PathLike) -> str:
    """The Summaries of a summaries file, each by its own ``as_html`` (one renderer for every consumer)."""
    try:
        summaries = read_summaries(path)
    except (OSError, ValueError) as e:  # json.JSONDecodeError is a ValueError
        raise ReportError(f"summaries {path} are not readable: {str(e).splitlines()[0]}") from None
    # each under its name in the job (a session, an estimator): the Summary's own title may not say it
    return '<div class="summaries">' + "".join(f'<p class="fid">{_esc(name)}</p>{s.as_html()}'
                                               for name, s in summaries.items()) + "</div>"


def _table_html(title: str, path: Path) -> str:
    head = f"<h3>{_esc(title)} <span class=\"fid\">{_esc(path.as_posix())}</span></h3>"
    if not path.is_file():
        return head + '\n<p class="note">not present (the stage has not run).</p>'
    if path.suffix == ".json":  # a summaries file (accelcal.summary.write_summaries)
        return head + "\n" + summaries_html(path)
    try:
        return head + "\n" + view_table(pd.read_csv(path), TABLE_VIEWS.get(path.as_posix()))
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as e:
        raise ReportError(f"table {path} is not a readable CSV: {str(e).splitlines()[0]}") from None


def _ledger_section(ledger) -> str:
    return ('<section><h2 id="claims">Claims ledger</h2><p class="note">Every claim of the three papers with '
            "the value this workflow computed and the verdict by the rule stated in the claim "
            f"(<code>results/claims.csv</code>). <code>{NOT_TESTABLE}</code>: the run's sample is too small for "
            "the rule to give both verdicts (the evidence gives the n it has and the n it needs); it is neither "
            "reproduced nor not reproduced.</p>" + ledger_html(ledger) + "</section>")


def _config_section(config, config_files) -> str:
    seeds = pd.DataFrame(seed_paths(config), columns=["key", "seed"])
    files = ", ".join(f"<code>{_esc(f)}</code>" for f in config_files) or "(none given)"
    return (f'<section><h2 id="config">Configuration and seeds</h2><p>Config file(s), each extending the ones '
            f"before it: {files}.</p>"
            f"<h3>Seeds</h3>{html_table(seeds)}<h3>The whole configuration</h3>{config_html(config)}</section>")


def _environment_section(lock_text: str) -> str:
    pins = pd.DataFrame(parse_lock(lock_text), columns=["package", "version", "only where"])
    digest = re.search(r"^# requirements-sha256: ([0-9a-f]+)$", lock_text, re.M)
    digest_html = f" Requirements digest <code>{digest.group(1)}</code>." if digest else ""
    return (f'<section><h2 id="environment">Package versions</h2><p>{len(pins)} pins of '
            f"<code>environment.lock</code> (installed by <code>tools/setup.sh</code> with hashes)."
            f"{digest_html}</p>{html_table(pins, max_rows=1000)}</section>")


def _walltime_section(benchmarks_dir) -> str:
    bench = read_benchmarks(benchmarks_dir)
    if bench.empty:
        times = '<p class="note">No benchmark files found.</p>'
    else:
        per_stage = stage_times(bench).rename(columns={"s": "wall time [s] (sum of jobs)",
                                                       "cpu_s": "CPU time [s] (sum of jobs)",
                                                       "max_rss": "largest peak memory [MB]"})
        per_job = bench.rename(columns={"s": "wall time [s]", "cpu_s": "CPU time [s]", "max_rss": "peak memory [MB]"})
        times = (f"{html_table(per_stage)}<p>Total over all jobs: {bench['s'].sum():.1f} s.</p>"
                 f"<details><summary>Per job</summary>{html_table(per_job, max_rows=1000)}</details>")
    return ('<section><h2 id="walltime">Wall time per stage</h2><p class="note">From Snakemake\'s benchmark files '
            "(<code>results/benchmarks/&lt;stage&gt;/&lt;job&gt;.tsv</code>) as they were when this page was built: "
            "the last run of each job, on whatever machine and load it ran. Jobs of a stage may have run in "
            f"parallel, so the sum is CPU-side work, not elapsed time.</p>{times}</section>")


def write_report(text: str, path: str | os.PathLike) -> Path:
    """Write the page atomically (a temporary file beside it, then rename)."""
    path = Path(path)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


__all__ = ["ReportError", "build_report", "embed_png", "figure_section", "load_conclusions", "parse_lock",
           "read_benchmarks", "read_claims", "render_caption", "seed_paths", "stage_times", "summaries_html",
           "write_report"]
