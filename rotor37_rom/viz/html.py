"""A self-contained HTML report: a summary table first, flagged runs, then sections of text, tables and figures.

Pure Python. Figures are referenced by paths relative to the report (copied next to it if they live elsewhere), so
the folder can be zipped and opened anywhere. The page has no script and loads nothing from the network.
"""
from __future__ import annotations

import dataclasses
import hashlib
import html
import math
import shutil
from pathlib import Path
from typing import Sequence

__all__ = ["Table", "Section", "write_report", "format_cell"]

_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:0.6em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}
th{background:#eee}td:first-child,th:first-child{text-align:left}figure{display:inline-block;margin:0.5em}
caption{text-align:left;font-weight:bold;padding:0.3em 0}
#summary td,#summary th{text-align:left}
img{max-width:520px;border:1px solid #ddd}figcaption{font-size:0.85em;color:#555;max-width:520px}
.flags{border:2px solid #c60;background:#fff4e6;padding:0.4em 1em;margin:1em 0}
.flags li{margin:0.2em 0}
.params{font-family:monospace;font-size:0.85em;background:#f6f6f6;padding:0.6em;white-space:pre-wrap}"""


@dataclasses.dataclass(frozen=True)
class Table:
    """A table: caption, column headers, rows of cells (written by ``format_cell``);
    ``html_id``: the id of the <table> element (the summary's is 'summary')."""

    caption: str
    header: Sequence[str]
    rows: Sequence[Sequence]
    html_id: str | None = None


@dataclasses.dataclass
class Section:
    """title; paragraphs (plain text); tables (``Table`` or (caption, header, rows)); figures: (path, caption);
    flags: warnings shown highlighted at the top of the section (e.g. a run that grew past the limit)."""

    title: str
    paragraphs: list = dataclasses.field(default_factory=list)
    tables: list = dataclasses.field(default_factory=list)
    figures: list = dataclasses.field(default_factory=list)
    flags: list = dataclasses.field(default_factory=list)


def format_cell(value) -> str:
    """The text of one cell: floats to 4 significant digits (whole numbers from 1,000 to 10^7 written out), NaN and
    None as '–', anything else as str()."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if isinstance(value, float):
        return f"{value:.0f}" if 1e3 <= abs(value) < 1e7 else f"{value:.4g}"
    return str(value)


def _table(table) -> str:
    if not isinstance(table, Table):
        table = Table(*table)
    ident = f" id='{html.escape(table.html_id)}'" if table.html_id else ""
    out = [f"<table{ident}><caption>{html.escape(table.caption)}</caption><tr>"
           + "".join(f"<th>{html.escape(str(h))}</th>" for h in table.header) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{html.escape(format_cell(v))}</td>" for v in row) + "</tr>" for row in table.rows]
    out.append("</table>")
    return "\n".join(out)


def _flags(flags: Sequence[str], html_id: str | None = None) -> str:
    ident = f" id='{html.escape(html_id)}'" if html_id else ""
    return (f"<div class='flags'{ident}><ul>" + "".join(f"<li>{html.escape(f)}</li>" for f in flags)
            + "</ul></div>") if flags else ""


def _figure(fig, caption: str, folder: Path) -> str:
    fig = Path(fig)
    if not fig.is_file():
        return f"<p><em>missing figure: {html.escape(str(fig))}</em></p>"
    try:
        rel = fig.resolve().relative_to(folder.resolve())
    except ValueError:                         # outside the report's folder: copy it in
        digest = hashlib.sha256(str(fig.resolve()).encode()).hexdigest()[:10]
        target = folder / "figures" / f"{digest}_{fig.name}"
        target.parent.mkdir(exist_ok=True)
        shutil.copyfile(fig, target)
        rel = target.relative_to(folder)
    return (f"<figure><img src='{html.escape(rel.as_posix())}' alt='{html.escape(caption)}'>"
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def write_report(path: str | Path, title: str, sections: Sequence[Section], parameters: dict | None = None,
                 summary: Table | None = None, flags: Sequence[str] = (), intro: Sequence[str] = ()) -> Path:
    """Write ``path`` (HTML, atomically): the title, ``intro`` paragraphs, the ``summary`` table (id 'summary'), the
    ``flags`` (id 'flags'), the sections, the parameters. Missing figures are listed as missing, not dropped."""
    path = Path(path)
    folder = path.parent
    folder.mkdir(parents=True, exist_ok=True)
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>"]
    out += [f"<p>{html.escape(p)}</p>" for p in intro]
    if summary is not None:
        out.append(_table(dataclasses.replace(summary, html_id=summary.html_id or "summary")))
    out.append(_flags(flags, "flags"))
    for section in sections:
        out.append(f"<h2>{html.escape(section.title)}</h2>")
        out.append(_flags(section.flags))
        out += [f"<p>{html.escape(p)}</p>" for p in section.paragraphs]
        out += [_table(t) for t in section.tables]
        out += [_figure(fig, caption, folder) for fig, caption in section.figures]
    if parameters:
        out.append("<h2>Run parameters</h2><div class='params'>"
                   + html.escape("\n".join(f"{k}: {v}" for k, v in parameters.items())) + "</div>")
    out.append("</body></html>")
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text("\n".join(out), encoding="utf-8")
    tmp.replace(path)
    return path
