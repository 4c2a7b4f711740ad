"""Figures of the reproduction: deterministic, atomically written PNG + PDF.

:func:`save_figure` writes ``<stem>.png`` and ``<stem>.pdf`` with fixed dpi and no
time stamps or software versions in the metadata, so that rerunning a figure gives
byte-identical files; each file is written to a temporary name in the target
directory and renamed, so a figure is never left half written.

Each stage's figure functions (e.g. :mod:`accelcal_repro.burkhard2024.figures`) take the
stage's tables, return a Figure drawn with :data:`RC` and :func:`style`, and leave the
writing to :func:`save_figure`.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # before pyplot: no display, deterministic raster backend

import matplotlib.pyplot as plt  # noqa: E402

from .atomic import atomic_output  # noqa: E402

DPI = 150
PNG_METADATA = {"Software": None}
PDF_METADATA = {"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None}

#: One style per method, shared by every figure.
METHOD_STYLE = {
    "full_lls": {"color": "C0", "marker": "o", "label": "full LLS"},
    "full_als": {"color": "C2", "marker": "s", "label": "full ALS"},
    "full_nlls": {"color": "C1", "marker": "x", "label": "full NLLS"},
    "bias_lls": {"color": "C3", "marker": "^", "label": "bias-only LLS"},
    "bias_nlls": {"color": "C4", "marker": "v", "label": "bias-only NLLS"},
    "full_lls_batch": {"color": "C0", "marker": "D", "label": "full LLS (batched)"},
    "bias_lls_batch": {"color": "C3", "marker": "D", "label": "bias-only LLS (batched)"},
    "full_als_batch": {"color": "C2", "marker": "D", "label": "full ALS (batched)"},
}

RC = {
    "figure.figsize": (7.0, 3.4),
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "legend.fontsize": 7.5,
    "svg.hashsalt": "accelcal",
    "pdf.fonttype": 42,
}


def style(method: str) -> dict:
    return METHOD_STYLE.get(method, {"color": "k", "marker": ".", "label": method})


def save_figure(fig, stem: str | os.PathLike) -> tuple[Path, Path]:
    """Write ``<stem>.png`` and ``<stem>.pdf`` deterministically and atomically; close ``fig``.

    Returns the two paths.
    """
    stem = Path(stem)
    if stem.suffix in (".png", ".pdf"):
        stem = stem.with_suffix("")
    png, pdf = stem.with_name(stem.name + ".png"), stem.with_name(stem.name + ".pdf")
    try:
        with atomic_output(png) as tmp:
            fig.savefig(tmp, format="png", dpi=DPI, metadata=PNG_METADATA)
        if fig.get_layout_engine() is not None:
            # keep the layout the PNG's draw computed: a constrained layout costs as much as
            # the rest of a draw again (half of the PDF's time on a figure of many panels)
            fig.set_layout_engine("none")
        with atomic_output(pdf) as tmp:
            fig.savefig(tmp, format="pdf", dpi=DPI, metadata=PDF_METADATA)
    finally:
        plt.close(fig)
    return png, pdf


__all__ = ["DPI", "METHOD_STYLE", "RC", "save_figure", "style"]
