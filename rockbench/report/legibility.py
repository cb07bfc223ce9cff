"""Figures that read at 100 % zoom: the size of their text as a reader sees it, and overlaps.

A report figure is a PNG of ``width_in * dpi`` pixels shown at most ``PAGE_PX`` pixels wide
(the page's content width in a 1400 px window, ``style.css``). A text of ``s`` points is then
``s * dpi / 72 * min(1, PAGE_PX / width_px)`` pixels tall on screen. :func:`make_legible` raises
every text below :data:`MIN_TEXT_PX` to it (and lets the figure's layout engine make room);
:func:`text_px` measures the smallest text as displayed; :func:`overlapping_texts` lists pairs of
tick labels, axis labels and titles whose boxes overlap once drawn. The report writes the
smallest size into each ``<img>`` (``data-text-px``) so the browser test can check it on the
page as shown.
"""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.text import Text

__all__ = ["MIN_TEXT_PX", "PAGE_PX", "display_scale", "text_px", "make_legible",
           "overlapping_texts", "wrap_at"]

#: Smallest text on screen [px] in a 1400 px window.
MIN_TEXT_PX = 11.0
#: Widest a figure is shown [px]: the page's content width in a 1400 px window (style.css:
#: max-width 1200 px less padding).
PAGE_PX = 1160.0


def _texts(fig: Figure) -> list[Text]:
    return [t for t in fig.findobj(Text)
            if t.get_visible() and t.get_text().strip() and t.figure is fig]


def display_scale(fig: Figure, dpi: float, page_px: float = PAGE_PX) -> float:
    """How much the page shrinks the figure's PNG (1: shown at its natural size)."""
    width_px = fig.get_figwidth() * dpi
    return min(1.0, page_px / width_px) if width_px > 0 else 1.0


def text_px(fig: Figure, dpi: float, page_px: float = PAGE_PX) -> float:
    """Height [px] of the smallest visible text of ``fig`` as shown on the page."""
    sizes = [t.get_fontsize() for t in _texts(fig)]
    if not sizes:
        return float("inf")
    return min(sizes) * dpi / 72.0 * display_scale(fig, dpi, page_px)


def make_legible(fig: Figure, dpi: float, *, min_px: float = MIN_TEXT_PX,
                 page_px: float = PAGE_PX) -> float:
    """Raise every text of ``fig`` smaller than ``min_px`` on screen to ``min_px`` (the layout
    engine, constrained or tight, then makes room when the figure is drawn); return the smallest
    text size on screen [px] afterwards."""
    scale = display_scale(fig, dpi, page_px)
    min_pt = min_px * 72.0 / (dpi * scale)
    for t in _texts(fig):
        if t.get_fontsize() < min_pt:
            t.set_fontsize(min_pt)
    return text_px(fig, dpi, page_px)


def overlapping_texts(fig: Figure, *, tolerance_px: float = 1.0) -> list[tuple[str, str]]:
    """Pairs of texts of one axes whose drawn boxes overlap by more than ``tolerance_px`` in
    both directions, as (text, text): tick labels of the same axis with each other (the
    crowded-log-axis case), and the axis labels and title with every tick label and each other.
    (An x and a y tick label meeting at the axes' corner is not counted.) Lays the figure out
    as drawing it would (its layout engine run, nothing rasterized: the PNG is drawn once,
    later)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)   # a Figure built without pyplot has no drawing canvas
    fig.draw_without_rendering()
    renderer = canvas.get_renderer()

    def shown(texts):
        return [(t.get_text(), t.get_window_extent(renderer)) for t in texts
                if t.get_visible() and t.get_text().strip()]

    def clash(a, b) -> bool:
        dx = min(a.x1, b.x1) - max(a.x0, b.x0)
        dy = min(a.y1, b.y1) - max(a.y0, b.y0)
        return dx > tolerance_px and dy > tolerance_px

    pairs: list[tuple[str, str]] = []
    for ax in fig.axes:
        xt, yt = shown(ax.get_xticklabels()), shown(ax.get_yticklabels())
        labels = shown([ax.xaxis.label, ax.yaxis.label, ax.title])
        for group in (xt, yt):
            pairs += [(a, b) for i, (a, ba) in enumerate(group) for b, bb in group[i + 1:]
                      if clash(ba, bb)]
        ticks = xt + yt
        for i, (a, ba) in enumerate(labels):
            pairs += [(a, b) for b, bb in ticks + labels[i + 1:] if clash(ba, bb)]
    return pairs


def wrap_at(text: str, sep: str, width: int) -> str:
    """``text`` broken after each ``sep`` into lines of about ``width`` characters: tick and
    column labels that stay apart without rotation (``"paper-asymmetric-hybrid-eps2"`` ->
    ``"paper-\\nasymmetric-\\nhybrid-eps2"`` with "-" and 12)."""
    lines, line = [], ""
    for part in str(text).split(sep):
        piece = part if not line else sep + part
        if line and len(line) + len(piece) > width:
            lines.append(line + sep)
            line = part
        else:
            line += piece
    lines.append(line)
    return "\n".join(lines)
