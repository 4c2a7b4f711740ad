"""Files of known static intervals: imucal section lists, JSON lists, CSV tables."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import RecordingError
from ..recording import Recording
from .parsing import norm_name, split_fields
from .text import is_comment, load_text


def read_intervals(path, rec: Recording) -> Recording:
    """``rec`` with the known static intervals of a file (replacing any it had).

    Accepted files:

    * an imucal section list (JSON ``{name: {"start": i, "end": j}}``, sample indices,
      end exclusive): every section whose name does not end in ``_rot``; the ``_rot``
      sections (imucal's rotations) become :attr:`Recording.rotations`;
    * JSON ``[[start, end], ...]`` or ``{"intervals": [...]}``: times [s] from the
      recording's start;
    * a CSV with columns ``start``, ``end`` (times [s] from the recording's start, or
      sample indices if the header says ``start_index``/``start_sample``) and an
      optional ``label``.

    A time interval covers the samples with ``start <= t <= end``.
    """
    path = Path(path)
    text, _ = load_text(path)
    stripped = text.lstrip()
    spans, labels, kind, rotations = [], [], "", rec.rotations
    if stripped.startswith("{") and '"start"' in stripped:
        sections = read_imucal_section_list(path)
        for name, (a, b) in sections.items():
            if not name.endswith("_rot"):
                spans.append((a, b))
                labels.append(name)
        rotations = {k: v for k, v in sections.items() if k.endswith("_rot")} or rotations
        kind = "imucal section list (samples; the *_rot sections are rotations)"
        idx = spans
    elif stripped.startswith(("[", "{")):
        try:
            obj = json.loads(text)
        except json.JSONDecodeError as e:
            raise RecordingError(f"{path}: not valid JSON ({' '.join(str(e).split())})") from None
        items = obj.get("intervals") if isinstance(obj, dict) else obj
        if not isinstance(items, list) or not all(isinstance(x, (list, tuple)) and len(x) == 2 for x in items):
            raise RecordingError(f"{path}: expected [[start, end], ...] in seconds or an imucal section list")
        try:
            spans = [(float(a), float(b)) for a, b in items]
        except (TypeError, ValueError):
            raise RecordingError(f"{path}: interval bounds must be numbers (seconds)") from None
        labels = [f"pose{k:02d}" for k in range(len(spans))]
        idx, kind = _time_spans_to_samples(spans, rec, path), "JSON list of [start, end] in s"
    else:
        tab = _interval_table(text, path)
        idx, labels, kind = tab(rec)
    if not idx:
        raise RecordingError(f"{path}: no static interval in the file")
    order = np.argsort([a for a, _ in idx], kind="stable")
    idx = [idx[i] for i in order]
    labels = [labels[i] for i in order]
    for a, b in idx:
        if not (0 <= a < b <= rec.n):
            raise RecordingError(f"{path}: interval {a}-{b} (samples) lies outside the recording's {rec.n} samples; "
                                 "are the bounds in seconds from the start of the recording?")
    rec = replace(rec, intervals=np.array(idx), labels=tuple(labels), rotations=rotations,
                  notes=rec.notes + (f"{len(idx)} known static intervals from {path.name} ({kind})",))
    return rec


def _time_spans_to_samples(spans, rec: Recording, path):
    out = []
    for a, b in spans:
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise RecordingError(f"{path}: interval ({a:g}, {b:g}) is not a range of times")
        i = int(np.searchsorted(rec.t, a, side="left"))
        j = int(np.searchsorted(rec.t, b, side="right"))
        if j - i < 2:
            raise RecordingError(f"{path}: interval {a:g}-{b:g} s holds fewer than 2 samples of the recording "
                                 f"(which lasts {rec.t[-1]:.4g} s)")
        out.append((i, j))
    return out


def _interval_table(text: str, path):
    lines = [ln for ln in text.splitlines() if ln.strip() and not is_comment(ln)]
    delim = next((d for d in ("\t", ";", ",") if d in lines[0]), " ")
    head = [norm_name(c) for c in split_fields(lines[0], delim)]
    col = {h: i for i, h in enumerate(head)}
    start = next((h for h in ("start", "starts", "startindex", "startsample", "tstart", "begin", "from") if h in col),
                 None)
    end = next((h for h in ("end", "stop", "endindex", "endsample", "stopindex", "tend", "tstop", "to") if h in col),
               None)
    if start is None or end is None:
        raise RecordingError(f"{path}: an interval file needs a header with start and end columns "
                             "(seconds, or start_index/end_index in samples)")
    samples = "index" in start or "sample" in start
    lab = next((h for h in ("label", "name", "pose", "section") if h in col), None)
    rows = [split_fields(ln, delim) for ln in lines[1:]]
    try:
        vals = [(float(r[col[start]]), float(r[col[end]])) for r in rows]
    except (ValueError, IndexError):
        raise RecordingError(f"{path}: every interval row needs numeric start and end") from None
    labels = [r[col[lab]] if lab is not None and len(r) > col[lab] else f"pose{k:02d}" for k, r in enumerate(rows)]

    def convert(rec):
        if samples:
            if any(a != int(a) or b != int(b) for a, b in vals):
                raise RecordingError(f"{path}: sample indices must be integers")
            return [(int(a), int(b)) for a, b in vals], labels, "CSV of sample ranges (end exclusive)"
        return _time_spans_to_samples(vals, rec, path), labels, "CSV of times in s"

    return convert


def read_imucal_section_list(json_path) -> dict[str, tuple[int, int]]:
    """Read an imucal section list: ``{name: (start, end)}``, half-open sample ranges.

    imucal slices with ``data.iloc[start:end]``, so ``end`` is exclusive.
    """
    path = Path(json_path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        raw = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise RecordingError(f"{path}: not valid JSON ({' '.join(str(e).split())})") from None
    if not isinstance(raw, dict) or not raw:
        raise RecordingError(f"{path}: expected a JSON object of sections {{name: {{start, end}}}}")
    out = {}
    for name, sec in raw.items():
        try:
            start, end = sec["start"], sec["end"]
        except (TypeError, KeyError):
            raise RecordingError(f"{path}: section {name!r} lacks integer 'start' and 'end'") from None
        if not (isinstance(start, int) and isinstance(end, int)) or isinstance(start, bool) \
                or isinstance(end, bool) or not 0 <= start < end:
            raise RecordingError(f"{path}: section {name!r} has invalid range start={start!r}, end={end!r}")
        out[str(name)] = (start, end)
    return out
