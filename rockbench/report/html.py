"""Building blocks of the self-contained HTML pages: the page itself (:func:`render_page`),
tables graded by agreement (:func:`html_table`, :func:`grade_legend`), embedded figures
(:func:`figure_html`), versions (:func:`versions_html`), conclusions (:func:`conclusion_html`).

Shared by the page of one comparison (:mod:`rockbench.report.case_page`) and the campaign page.
Figures are embedded as base64 PNG and the CSS inlined: a page needs no network. The page
template and style sheet are package data (``page.html``, ``style.css``) filled with
:class:`string.Template`; no template engine is needed. What the pages show and how to read
them: ``docs/report.md``.
"""

from __future__ import annotations

import datetime as _dt
import platform
import string
from collections.abc import Iterable, Mapping, Sequence
from html import escape
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..comparison import DERIVED_COLUMNS, TOLERANCES, with_derived  # noqa: F401 (re-exported)
from . import figures as F

__all__ = [
    "html_metric_table",
    "conclusion_html",
    "figure_html",
    "fmt",
    "grade_legend",
    "html_table",
    "render_page",
    "versions",
    "versions_html",
]

_TEXT_COLUMNS = {"backend", "status", "reason", "engine_version", "scene", "shape", "frame",
                 "record", "case", "engine", "motion"}


def fmt(value: Any) -> str:
    """A table cell: 4 significant digits, yes/no for booleans, empty for missing values."""
    try:
        if value is pd.NA or value is pd.NaT:
            return ""
    except TypeError:  # pragma: no cover
        pass
    return F._fmt(value)


# ------------------------------------------------------------------------------------------
# Page building blocks
# ------------------------------------------------------------------------------------------
def _resource(name: str) -> str:
    return resources.files("rockbench.report").joinpath(name).read_text(encoding="utf-8")


def render_page(title: str, sections: Sequence[tuple[str, str, str]], *,
                subtitle: str = "") -> str:
    """The whole page: ``sections`` are (anchor id, heading, inner HTML) in order."""
    from .. import __version__

    body = "\n".join(f'<section id="{escape(sid)}">\n<h2>{escape(head)}</h2>\n{inner}\n'
                     f"</section>" for sid, head, inner in sections)
    nav = " ".join(f'<a href="#{escape(sid)}">{escape(head)}</a>' for sid, head, _ in sections)
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return string.Template(_resource("page.html")).substitute(
        title=escape(title), subtitle=escape(subtitle), css=_resource("style.css"), nav=nav,
        body=body, version=escape(__version__), generated=now)


def _unit(units: Mapping[str, str] | None, col: str) -> tuple[str, str]:
    if not units or col not in units:
        return "", ""
    text = units[col]
    unit = text.split(",", 1)[0].strip()
    return unit, text


def html_table(df: pd.DataFrame, columns: Sequence[str] | None = None, *,
               units: Mapping[str, str] | None = None, graded: bool = True,
               grade_as: Mapping[str, str] | None = None, table_id: str | None = None,
               scroll: bool = False) -> str:
    """An HTML table of ``df``; each header shows the column's unit (from ``units``: column ->
    "unit, definition", the definition as a tooltip); with ``graded`` each cell of a graded
    metric gets the class good / fair / poor (:func:`rockbench.report.figures.grade`).
    ``grade_as`` maps a displayed column to the metric whose thresholds grade it."""
    cols = [c for c in (columns if columns is not None else df.columns) if c in df.columns]
    grade_as = dict(grade_as or {})
    # a column of words wraps (left-aligned); numbers stay on one line
    text_cols = {c for c in cols if c in _TEXT_COLUMNS or _wordy(df[c])}
    head = []
    for c in cols:
        unit, text = _unit(units, c)
        cls = ' class="txt"' if c in text_cols else ""
        tip = f' title="{escape(text)}"' if text else ""
        # a long column name breaks after its underscores, so the table fits the page
        label = escape(c).replace("_", "_<wbr>") + (f"<br><small>[{escape(unit)}]</small>"
                                                    if unit else "")
        head.append(f"<th{cls}{tip}>{label}</th>")
    rows = []
    for rec in df[cols].itertuples(index=False):
        cells = []
        for c, v in zip(cols, rec):
            classes = []
            if c in text_cols:
                classes.append("txt")
            if graded:
                g = F.grade(grade_as.get(c, c), None if _missing(v) else v)
                if g != "na":
                    classes.append(g)
            cls = f' class="{" ".join(classes)}"' if classes else ""
            cells.append(f"<td{cls}>{escape(fmt(v))}</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    tid = f' id="{escape(table_id)}"' if table_id else ""
    html = (f"<table{tid}>\n<thead><tr>{''.join(head)}</tr></thead>\n<tbody>\n"
            + "\n".join(rows) + "\n</tbody>\n</table>")
    return f'<div class="scroll">{html}</div>' if scroll else html


def html_metric_table(df: pd.DataFrame, columns: Sequence[str], *, key: str = "backend",
                      units: Mapping[str, str] | None = None, table_id: str | None = None
                      ) -> str:
    """``df`` transposed: one row per column of ``columns`` (its name, unit and definition as a
    tooltip), one column per row of ``df`` (headed by its ``key``), each cell graded as
    :func:`html_table` grades the metric. For a few rows with many metrics (a case's
    backends): it stays as narrow as the page."""
    cols = [c for c in columns if c in df.columns and c != key]
    head = "".join(f'<th class="txt">{escape(str(k))}</th>' for k in df[key])
    rows = []
    for c in cols:
        unit, text = _unit(units, c)
        tip = f' title="{escape(text)}"' if text else ""
        label = escape(c) + (f" <small>[{escape(unit)}]</small>" if unit else "")
        cells = []
        for v in df[c]:
            g = F.grade(c, None if _missing(v) else v)
            cls = f' class="{g}"' if g != "na" else ""
            cells.append(f"<td{cls}>{escape(fmt(v))}</td>")
        rows.append(f'<tr><th class="txt"{tip}>{label}</th>{"".join(cells)}</tr>')
    tid = f' id="{escape(table_id)}"' if table_id else ""
    return (f'<table{tid}>\n<thead><tr><th class="txt">metric</th>{head}</tr></thead>\n'
            f"<tbody>\n" + "\n".join(rows) + "\n</tbody>\n</table>")


def _wordy(col: pd.Series) -> bool:
    """Whether a column holds text longer than a short label (it then wraps)."""
    if col.dtype != object and str(col.dtype) not in ("string", "str"):
        return False
    return any(isinstance(v, str) and len(v) > 16 for v in col)


def _missing(v: Any) -> bool:
    if v is None:
        return True
    try:
        return bool(pd.isna(v))
    except (TypeError, ValueError):
        return False


def grade_legend() -> str:
    """One line explaining the cell colours, with the thresholds."""
    parts = []
    for m, (good, fair) in TOLERANCES["grades"].items():
        parts.append(f"{escape(m)}: good &le; {good:g}, fair &le; {fair:g}")
    return ('<p class="legend"><span class="good">good</span><span class="fair">fair</span>'
            '<span class="poor">poor</span> Thresholds on |value| (units as in the table: '
            + "; ".join(parts) + "); verdict_agrees: no is poor; energy_gained_at_impact and "
            "contact_opened: yes is fair; a status other than ok is poor. See docs/report.md."
            "</p>")


def figure_html(fig, caption: str, *, name: str | None = None,
                png_dir: str | Path | None = None, dpi: int = 100) -> str:
    """A ``<figure>`` with the figure embedded as a base64 PNG ``data:`` URI; when ``png_dir``
    and ``name`` are given the PNG is also written to ``png_dir/name.png``. The figure is
    closed (its memory released) afterwards.

    Every text is first raised to at least :data:`~rockbench.report.legibility.MIN_TEXT_PX`
    pixels as shown in a 1400 px window (:func:`~rockbench.report.legibility.make_legible`);
    the ``<img>`` carries that size (``data-text-px``, at its natural width) and the number of
    overlapping labels (``data-overlaps``, :func:`~rockbench.report.legibility.overlapping_texts`)
    for the tests."""
    import base64

    from .legibility import display_scale, make_legible, overlapping_texts

    shown_px = make_legible(fig, dpi)
    natural_px = shown_px / display_scale(fig, dpi)
    overlaps = len(overlapping_texts(fig))
    png = F.png_bytes(fig, dpi=dpi)
    fig.clear()
    if png_dir is not None and name:
        d = Path(png_dir)
        d.mkdir(parents=True, exist_ok=True)
        (d / f"{name}.png").write_bytes(png)
    uri = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
    fid = f' id="fig-{escape(name)}"' if name else ""
    return (f'<figure{fid}><img src="{uri}" alt="{escape(caption)}" '
            f'data-text-px="{natural_px:.2f}" data-overlaps="{overlaps}">'
            f"<figcaption>{escape(caption)}</figcaption></figure>")


def versions(engines: Mapping[str, str] | None = None) -> dict[str, Any]:
    """Versions of rockbench, Python, the platform and the scientific stack, and of the engines
    in ``engines`` (backend name -> engine version, or why it is unavailable: the report does
    not import engines, so the caller says which ran; e.g. the ``engine_version`` column of a
    comparison table)."""
    import matplotlib
    import scipy

    from .. import __version__

    from ..machine import describe

    m = describe()
    out: dict[str, Any] = {
        "rockbench": __version__,
        "python": m["python"],
        "platform": m["platform"],
        "machine": platform.machine(),
        "processor": m["processor"],
        "cpu_count": m["cores"],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "pandas": pd.__version__,
        "matplotlib": matplotlib.__version__,
    }
    for name, version in (engines or {}).items():
        out[f"engine {name}"] = version
    return out


def _dl(items: Iterable[tuple[str, Any]]) -> str:
    return ('<dl class="settings">' + "".join(
        f"<dt>{escape(str(k))}</dt><dd>{escape(_plain(v))}</dd>" for k, v in items) + "</dl>")


def _plain(v: Any) -> str:
    if isinstance(v, float):
        return fmt(v)
    if isinstance(v, Mapping):
        return ", ".join(f"{k}={_plain(x)}" for k, x in v.items())
    if isinstance(v, (list, tuple)):
        return ", ".join(_plain(x) for x in v)
    return "" if v is None else str(v)


def versions_html(engines: Mapping[str, str] | None = None) -> str:
    """The versions (:func:`versions`) as a definition list."""
    return _dl(versions(engines).items())


def conclusion_html(lines: Sequence[str]) -> str:
    """Plain-language findings as the page's conclusion list."""
    return '<div id="conclusion"><ul>' + "".join(f"<li>{escape(s)}</li>" for s in lines) \
        + "</ul></div>"
