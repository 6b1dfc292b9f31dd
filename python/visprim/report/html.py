"""A single self-contained ``index.html`` page showing the report's figures and tables."""

from __future__ import annotations

import html
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from visprim.accuracy import ErrorTable, _fmt

#: The style sheet of the report pages (``visprim report`` and ``visprim evaluate``).
CSS = """
body { font-family: system-ui, sans-serif; max-width: 1150px; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #ddd; }
figure { margin: 1.2em 0; } figure img { max-width: 100%; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th { background: #f4f4f4; } caption { text-align: left; font-weight: bold; padding: 0.3em 0; }
pre { background: #f7f7f7; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
.note { font-size: 0.85em; color: #555; }
nav.toc { background: #fafafa; border: 1px solid #e4e4e4; padding: 0.5em 1.2em; }
nav.toc ol { margin: 0.3em 0; } .gifs img { max-width: 32%; margin-right: 1%; }
.scroll { overflow-x: auto; max-width: 100%; } .scroll table { margin: 0.4em 0; }
td:first-child, th:first-child { text-align: left; }
"""


def slug(heading: str) -> str:
    """An HTML anchor id for a heading ("Tables 1–3" → "tables-1-3")."""
    out = []
    for ch in heading.lower():
        out.append(ch if ch.isascii() and ch.isalnum() else "-")
    return "-".join(p for p in "".join(out).split("-") if p) or "section"


@dataclass
class Page:
    """Sections of the page, in order: ("h2 title", html body)."""

    title: str
    intro: str = ""
    sections: list[tuple[str, str]] = field(default_factory=list)

    def add(self, heading: str, body_html: str) -> None:
        self.sections.append((heading, body_html))

    def render(self) -> str:
        ids: list[str] = []
        for heading, _ in self.sections:
            base = slug(heading)
            ident, n = base, 2
            while ident in ids:
                ident, n = f"{base}-{n}", n + 1
            ids.append(ident)
        toc = "".join(
            f'<li><a href="#{i}">{html.escape(h)}</a></li>'
            for i, (h, _) in zip(ids, self.sections, strict=True)
        )
        parts = [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            f"<title>{html.escape(self.title)}</title>",
            f"<style>{CSS}</style></head><body>",
            f"<h1>{html.escape(self.title)}</h1>",
            self.intro,
        ]
        if self.sections:
            parts.append(f'<nav class="toc"><strong>Contents</strong><ol>{toc}</ol></nav>')
        for ident, (heading, body) in zip(ids, self.sections, strict=True):
            parts.append(f'<h2 id="{ident}">{html.escape(heading)}</h2>')
            parts.append(body)
        parts.append("</body></html>")
        return "\n".join(parts) + "\n"

    def write(self, path: Path) -> Path:
        path.write_text(self.render(), encoding="utf-8")
        return path


def figure(src: str, caption: str) -> str:
    """An <img> with a caption (``src`` relative to the page)."""
    return (
        f'<figure><img src="{html.escape(src)}" alt="{html.escape(caption)}">'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _inline(text: str) -> str:
    """Escaped text with Markdown's ``**bold**``."""
    return re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", html.escape(text))


def _table_html(rows: Sequence[Sequence[str]]) -> str:
    head = "".join(f"<th>{_inline(c)}</th>" for c in rows[0])
    body = "".join(
        "<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in rows[1:]
    )
    return f'<div class="scroll"><table><tr>{head}</tr>{body}</table></div>'


def markdown_to_html(text: str) -> str:
    """The Markdown visprim writes as an HTML fragment (every text escaped): ``#``/``##``
    headings, ``- `` items, pipe tables (header, rule, rows), paragraphs (blank-line
    separated) and ``**bold**``. The one converter of the report, the demo's comparison and
    ``evaluate.html``."""
    out: list[str] = []
    rows: list[list[str]] = []
    para: list[str] = []

    def flush() -> None:
        if rows:
            out.append(_table_html(rows))
            rows.clear()
        if para:
            out.append(f"<p>{_inline(' '.join(para))}</p>")
            para.clear()

    for line in text.splitlines():
        s = line.strip()
        if s.startswith("|"):
            if para:
                flush()
            cells = [c.strip() for c in s.strip("|").split("|")]
            if not all(c and set(c) <= set("-:") for c in cells):
                rows.append(cells)
            continue
        if rows:
            flush()
        if not s:
            flush()
        elif s.startswith("## ") or s.startswith("# ") or s.startswith("- "):
            flush()
            if s.startswith("- "):
                out.append(f"<p>• {_inline(s[2:])}</p>")
            else:
                level = 2 if s.startswith("## ") else 1
                out.append(f"<h{level}>{_inline(s[level + 1 :])}</h{level}>")
        else:
            para.append(s)
    flush()
    return "\n".join(out)


def markdown_table(text: str) -> str:
    """A pipe-delimited Markdown table (header, rule, rows) as an HTML table
    (:func:`markdown_to_html`)."""
    return markdown_to_html(text)


def table(t: ErrorTable, links: Sequence[tuple[str, str]] = ()) -> str:
    """An :class:`~visprim.accuracy.ErrorTable` as an HTML table (+ links to its files)."""
    head = "".join(f"<th>{html.escape(c)}</th>" for c in t.columns)
    rows = "".join(
        "<tr>" + "".join(f"<td>{html.escape(_fmt(v))}</td>" for v in r) + "</tr>" for r in t.rows
    )
    notes = "".join(f'<p class="note">{html.escape(n)}</p>' for n in t.notes)
    link = ""
    if links:
        link = (
            '<p class="note">'
            + " · ".join(
                f'<a href="{html.escape(h)}">{html.escape(label)}</a>' for label, h in links
            )
            + "</p>"
        )
    return (
        f"<table><caption>{html.escape(t.title)}</caption><tr>{head}</tr>{rows}</table>"
        f"{notes}{link}"
    )


def pre(text: str) -> str:
    """Preformatted text."""
    return f"<pre>{html.escape(text)}</pre>"


def paragraph(text: str) -> str:
    """A paragraph of plain text."""
    return f"<p>{html.escape(text)}</p>"
