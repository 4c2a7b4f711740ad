"""One type for what every result says in a few lines: :class:`Summary` (statsmodels' idea).

Every result the command line prints or the report shows (an accelerometer, gyroscope or
magnetometer calibration, a discrepancy report or its deterministic layer, a noise report)
has ``summary(*, written_to=None, ...)`` returning a :class:`Summary`.  The text is the
string itself (``print`` it; it compares and concatenates as a ``str``); the same content
renders as a dict (:meth:`Summary.as_dict`, JSON) and as HTML (:meth:`Summary.as_html`).
Its structure is read from the lines, so every renderer says the same: the first line is
the title, a line starting with ``warning:`` is a warning, the others are the body with
their indentation.
"""

from __future__ import annotations

import html

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
        return [x for x in self.splitlines()[1:] if not x.startswith(WARNING)]

    @property
    def warnings(self) -> list[str]:
        return [x[len(WARNING):].strip() for x in self.splitlines() if x.startswith(WARNING)]

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


__all__ = ["Summary"]
