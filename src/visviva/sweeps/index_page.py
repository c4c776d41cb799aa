"""``index.html``: one page for a sweep's results, opened from the sweep's directory.

The page is one self-contained file (its style and its few lines of script inline; no request
leaves the directory, and it works from ``file://``): the sweep's name, description and counts,
links to the tables, each plot (``plots/<name>.png``) with its table, and the table of runs: the
index (a link to the run's directory), the values, the outcome, a few figures, links to the
files the run wrote and the error of a failed run. Clicking a column's header sorts the runs by
it. Every text that comes from the user (names, description, values, errors) is escaped; links
are relative and percent-encoded.
"""

from __future__ import annotations

import html
import os
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from ..io.files import atomic_path
from .reductions import shown

__all__ = ["MAX_LISTED_RUNS", "write_index"]

#: Most runs listed on the page (every run is in results.csv); keeps the page a few MB at most.
MAX_LISTED_RUNS = 5000
#: Figures of each run shown in the table, when some run has them.
KEY_FIGURES = ("steps", "t_reached_s", "energy_drift", "max_energy_error", "wall_time_s")
#: Characters of a failed run's error shown in the table.
_ERROR_WIDTH = 160
#: Files listed first among a run's outputs; the others follow by name.
_FIRST = ("summary.json", "recording.h5")

_STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 1.5em auto; max-width: 110em;
       padding: 0 1em; color: #1d2330; background: #fbfcfd; }
h1 { margin-bottom: 0.2em; } .description { white-space: pre-wrap; max-width: 60em; }
.counts { font-weight: 600; } .warning { color: #8a4b00; }
figure { display: inline-block; margin: 0 1em 1.5em 0; vertical-align: top; }
figure img { max-width: 100%; height: auto; border: 1px solid #d8dde6; background: #fff; }
figcaption { font-size: 13px; }
table { border-collapse: collapse; font-size: 13px; }
th, td { padding: 0.25em 0.6em; border-bottom: 1px solid #e3e7ee; text-align: left;
         vertical-align: top; }
th { position: sticky; top: 0; background: #eef1f5; cursor: pointer; user-select: none; }
th[aria-sort="ascending"]::after { content: " \\25B2"; }
th[aria-sort="descending"]::after { content: " \\25BC"; }
td.number { text-align: right; font-variant-numeric: tabular-nums; }
tr.failed { background: #fdf0ef; } td.error { min-width: 28em; }
.scroll { overflow-x: auto; }
td.files { white-space: nowrap; } td.files a { margin-right: 0.5em; }
"""

# Sorts the runs by the clicked column: numbers by value (each cell's data-value), other cells
# by their text; empty cells last; a second click reverses.
_SCRIPT = """
document.querySelectorAll("#runs th").forEach((header, column) => {
  header.addEventListener("click", () => {
    const body = document.querySelector("#runs tbody");
    const up = header.getAttribute("aria-sort") !== "ascending";
    document.querySelectorAll("#runs th").forEach(h => h.removeAttribute("aria-sort"));
    header.setAttribute("aria-sort", up ? "ascending" : "descending");
    const key = row => {
      const cell = row.cells[column];
      const text = cell.dataset.value ?? cell.textContent.trim();
      return text === "" ? null : (isNaN(Number(text)) ? text : Number(text));
    };
    const rows = Array.from(body.rows);
    rows.sort((a, b) => {
      const x = key(a), y = key(b);
      if (x === null || y === null) return (x === null) - (y === null);
      const order = typeof x === typeof y ? (x < y ? -1 : x > y ? 1 : 0)
                                          : String(x).localeCompare(String(y));
      return up ? order : -order;
    });
    body.append(...rows);
  });
});
"""


def _e(text: Any) -> str:
    """User text, escaped for HTML text and attribute values alike."""
    return html.escape(str(text), quote=True)


def _href(*parts: str) -> str:
    """A relative link to ``parts`` (percent-encoded, then escaped for the attribute)."""
    return _e("/".join(quote(part) for part in parts))


def _cell(value: Any) -> str:
    """A table cell: numbers right-aligned and sortable by value."""
    if value is None:
        return "<td></td>"
    if isinstance(value, bool):
        return f'<td data-value="{int(value)}">{"yes" if value else "no"}</td>'
    if isinstance(value, (int, float)):
        return f'<td class="number" data-value="{_e(repr(value))}">{_e(shown(value))}</td>'
    return f"<td>{_e(shown(value))}</td>"


def _outputs(directory: Path) -> list[str]:
    """The files (and folders, such as an OBJ sequence) a run left, summary first."""
    try:
        names = [e.name for e in os.scandir(directory) if not e.name.startswith(".")]
    except OSError:
        return []
    return sorted(names, key=lambda n: (_FIRST.index(n) if n in _FIRST else len(_FIRST), n))


def write_index(
    directory: Path,
    heading: Mapping[str, Any],
    parameters: Sequence[str],
    rows: Sequence[Mapping[str, Any]],
    plots: Sequence[tuple[str, str]],
    warnings: Sequence[str] = (),
) -> Path:
    """Write ``directory/index.html`` atomically; return its path.

    Args:
        directory: The sweep's directory (holding ``runs/``, ``plots/`` and the tables).
        heading: ``sweep`` (name), ``description``, ``design``, ``seed`` and ``runs_total``.
        parameters: The parameters' paths.
        rows: The results table, one mapping per run.
        plots: ``(name, title)`` of each plot whose image was written to ``plots/<name>.png``.
        warnings: Problems met while writing the results (a plot not drawn), shown on top.
    """
    name = str(heading.get("sweep", "sweep"))
    failed = sum(1 for row in rows if not row.get("success"))
    total = int(heading.get("runs_total", len(rows)))
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(name)}: sweep results</title>",
        f"<style>{_STYLE}</style></head><body>",
        f"<h1>{_e(name)}</h1>",
    ]
    if heading.get("description"):
        parts.append(f'<p class="description">{_e(heading["description"])}</p>')
    unfinished = f" ({total - len(rows)} not finished)" if len(rows) < total else ""
    parts += [
        f'<p class="counts">{len(rows)} of {total} runs{unfinished}: {len(rows) - failed} '
        f"succeeded, {failed} failed</p>",
        f"<p>{_e(heading.get('design', 'grid'))} design, seed {_e(heading.get('seed', 0))}; "
        f"parameters: {_e(', '.join(parameters))}. Tables: "
        + " · ".join(
            f'<a href="{_href(table)}">{table}</a>'
            for table in ("results.csv", "results.json", "results.h5")
            if (directory / table).is_file()
        )
        + "</p>",
    ]
    parts += [f'<p class="warning">warning: {_e(text)}</p>' for text in warnings]
    if plots:
        parts.append("<h2>Plots</h2>")
    for stem, title in plots:
        extra = " · ".join(
            f'<a href="{_href("plots", stem + suffix)}">{suffix.lstrip(".").upper()}</a>'
            for suffix in (".csv", ".svg")
            if (directory / "plots" / (stem + suffix)).is_file()
        )
        parts.append(
            f'<figure><img src="{_href("plots", stem + ".png")}" alt="{_e(title)}">'
            f"<figcaption>{_e(title)} {extra}</figcaption></figure>"
        )
    parts.append(_runs_table(directory, parameters, rows))
    parts.append(f"<script>{_SCRIPT}</script></body></html>")
    target = directory / "index.html"
    with atomic_path(target) as temporary:
        temporary.write_text("\n".join(parts) + "\n", encoding="utf-8")
    return target


def _runs_table(
    directory: Path, parameters: Sequence[str], rows: Sequence[Mapping[str, Any]]
) -> str:
    """The ``<h2>`` and ``<table>`` of the runs (the first :data:`MAX_LISTED_RUNS`)."""
    figures = [f for f in KEY_FIGURES if any(row.get(f) is not None for row in rows)]
    headers = ["index", *parameters, "success", *figures, "files", "error"]
    listed = rows[:MAX_LISTED_RUNS]
    more = (
        f" (the first {len(listed)} of {len(rows)}; all are in results.csv)"
        if len(rows) > len(listed)
        else ""
    )
    parts = [
        f"<h2>Runs{more}</h2>",
        '<div class="scroll"><table id="runs"><thead><tr>',
        *(f"<th>{_e(header)}</th>" for header in headers),
        "</tr></thead><tbody>",
    ]
    for row in listed:
        run = str(row.get("run") or "")
        files = _outputs(directory / "runs" / run) if run else []
        links = " ".join(f'<a href="{_href("runs", run, file)}">{_e(file)}</a>' for file in files)
        # The index links to the run's directory, and names it on hovering.
        index = row.get("index")
        number = (
            f'<td class="number" data-value="{_e(index)}"><a href="{_href("runs", run)}/" '
            f'title="{_e(run)}">{_e(index)}</a></td>'
            if files
            else _cell(index)
        )
        error = str(row.get("error") or "")
        # The first sentence in the table (the advisor's advice can run to a paragraph); the
        # whole message shows on hovering, and is in results.csv.
        brief = textwrap.shorten(error.split(". ")[0], _ERROR_WIDTH, placeholder=" …")
        parts.append(
            f'<tr class="{"ok" if row.get("success") else "failed"}">{number}'
            + "".join(_cell(row.get(h)) for h in (*parameters, "success", *figures))
            + f'<td class="files">{links}</td>'
            + (f'<td class="error" title="{_e(error)}">{_e(brief)}</td>' if error else "<td></td>")
            + "</tr>"
        )
    parts.append("</tbody></table></div>")
    return "\n".join(parts)
