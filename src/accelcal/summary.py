"""One type for what every result says in a few lines: :class:`Summary` (statsmodels' idea).

Every result the command line prints or the report shows (an accelerometer, gyroscope or
magnetometer calibration, a discrepancy report or its deterministic layer, a noise report)
has ``summary(*, written_to=None, ...)`` returning a :class:`Summary`.  The text is the
string itself (``print`` it; it compares and concatenates as a ``str``); the same content
renders as a dict (:meth:`Summary.as_dict`, JSON) and as HTML (:meth:`Summary.as_html`).
Its structure is read from the lines, so every renderer says the same: the first line is
the title, a line starting with ``warning:`` (after its indentation: a sensor's warnings
nested under it) is a warning, the others are the body with their indentation.

A workflow job that makes results keeps their summaries for the report
(:func:`write_summaries`, a JSON of the texts: the text is the whole Summary), and the report
renders each read back (:func:`read_summaries`) with :meth:`Summary.as_html`.
"""

from __future__ import annotations

import html
import json
import os
from collections.abc import Mapping

from .atomic import write_json_atomic

WARNING = "warning:"


class Summary(str):
    """A result in a few lines: text (the ``str`` itself), :meth:`as_dict`, :meth:`as_html`."""

    def __new__(cls, lines):
        if isinstance(lines, str):
            lines = lines.splitlines()
        return super().__new__(cls, "\n".join(str(x) for x in lines))

    @property
    def title(self) -> str:
        return self.splitlines()[0] if self else ""

    @property
    def body(self) -> list[str]:
        """The lines after the title that are not warnings (indentation kept)."""
        return [x for x in self.splitlines()[1:] if not _is_warning(x)]

    @property
    def warnings(self) -> list[str]:
        return [x.strip()[len(WARNING):].strip() for x in self.splitlines() if _is_warning(x)]

    def as_text(self) -> str:
        return str(self)

    def as_dict(self) -> dict:
        return {"title": self.title, "lines": self.body, "warnings": self.warnings}

    def as_html(self) -> str:
        """A ``<section>``: the title as a heading, the body as preformatted lines, the warnings as a list."""
        parts = [f"<section class=\"summary\"><h4>{html.escape(self.title)}</h4>"]
        if self.body:
            parts.append("<pre>" + html.escape("\n".join(self.body)) + "</pre>")
        if self.warnings:
            parts.append("<ul class=\"warnings\">" + "".join(f"<li>{html.escape(w)}</li>" for w in self.warnings)
                         + "</ul>")
        return "".join(parts) + "</section>"


def _is_warning(line: str) -> bool:
    return line.lstrip().startswith(WARNING)


def write_summaries(path: str | os.PathLike, summaries: Mapping[str, Summary]) -> None:
    """Keep ``{name: Summary}`` for the report: ``{"summaries": {name: text}}``, written whole or not at all."""
    write_json_atomic(path, {"summaries": {str(k): str(v) for k, v in summaries.items()}})


def read_summaries(path: str | os.PathLike) -> dict[str, Summary]:
    """``{name: Summary}`` of a file :func:`write_summaries` wrote (in its order)."""
    with open(path, encoding="utf-8") as fh:
        data = json.load(fh)
    if not isinstance(data, dict) or not isinstance(data.get("summaries"), dict):
        raise ValueError(f"{path} is not a summaries file (a JSON object with a 'summaries' mapping)")
    return {k: Summary(v) for k, v in data["summaries"].items()}


__all__ = ["Summary", "read_summaries", "write_summaries"]
