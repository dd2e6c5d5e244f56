"""A self-contained HTML report: sections of text, tables (numbers next to the paper's) and figures.

Pure Python. Figures are referenced by paths relative to the report (copied next to it if they live elsewhere), so
the folder can be zipped and opened anywhere.
"""
from __future__ import annotations

import dataclasses
import html
import shutil
from pathlib import Path

__all__ = ["Section", "write_report"]

_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:0.6em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}
th{background:#eee}td:first-child,th:first-child{text-align:left}figure{display:inline-block;margin:0.5em}
img{max-width:520px;border:1px solid #ddd}figcaption{font-size:0.85em;color:#555;max-width:520px}
.params{font-family:monospace;font-size:0.85em;background:#f6f6f6;padding:0.6em;white-space:pre-wrap}"""


@dataclasses.dataclass
class Section:
    """title; paragraphs (plain text); tables: (caption, header, rows); figures: (path, caption)."""

    title: str
    paragraphs: list = dataclasses.field(default_factory=list)
    tables: list = dataclasses.field(default_factory=list)
    figures: list = dataclasses.field(default_factory=list)


def _cell(value) -> str:
    if isinstance(value, float):
        return html.escape(f"{value:.4g}")
    return html.escape(str(value))


def write_report(path: str | Path, title: str, sections: list[Section], parameters: dict | None = None) -> Path:
    """Write ``path`` (HTML); missing figures are listed as missing rather than silently dropped."""
    path = Path(path)
    folder = path.parent
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "figures").mkdir(exist_ok=True)
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>"]
    for section in sections:
        out.append(f"<h2>{html.escape(section.title)}</h2>")
        out += [f"<p>{html.escape(p)}</p>" for p in section.paragraphs]
        for caption, header, rows in section.tables:
            out.append(f"<table><caption>{html.escape(caption)}</caption><tr>"
                       + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>")
            out += ["<tr>" + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>" for row in rows]
            out.append("</table>")
        for fig, caption in section.figures:
            fig = Path(fig)
            if not fig.is_file():
                out.append(f"<p><em>missing figure: {html.escape(str(fig))}</em></p>")
                continue
            try:
                rel = fig.resolve().relative_to(folder.resolve())
            except ValueError:
                target = folder / "figures" / f"{abs(hash(str(fig.resolve()))) % 10**8}_{fig.name}"
                shutil.copyfile(fig, target)
                rel = target.relative_to(folder)
            out.append(f"<figure><img src='{html.escape(str(rel))}' alt='{html.escape(caption)}'>"
                       f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    if parameters:
        out.append("<h2>Run parameters</h2><div class='params'>"
                   + html.escape("\n".join(f"{k}: {v}" for k, v in parameters.items())) + "</div>")
    out.append("</body></html>")
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text("\n".join(out))
    tmp.replace(path)
    return path
