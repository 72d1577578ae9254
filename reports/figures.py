"""Matplotlib figures as bytes: PNG files beside CSV tables, SVG inline in the HTML report.

Matplotlib loads on the first figure only (`gliderplan check` never pays for it). SVG text
stays text (`svg.fonttype: none`): the page uses the reader's own sans-serif font, never
an external one, and the figure stays small and searchable.
"""

from __future__ import annotations

import io
from typing import Any


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "gliderplan",
                         "font.family": "sans-serif"})
    return plt


def render(fig: Any, fmt: str) -> bytes:
    """The figure as `fmt` ("png" or "svg") bytes; the figure is closed."""
    plt = pyplot()
    buffer = io.BytesIO()
    metadata = {"Date": None} if fmt == "svg" else {}
    try:
        fig.savefig(buffer, format=fmt, metadata=metadata, bbox_inches="tight")
    finally:
        plt.close(fig)
    return buffer.getvalue()
