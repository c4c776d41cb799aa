"""Run the code blocks of a Markdown page as a reader would: in order, in one scratch directory.

What runs:

- Fenced blocks tagged ``python`` or ``bash``. Other tags (``toml``, ``text``, none) are
  prose. A ``python`` block that starts with ``>>>`` is a doctest, run by pytest's
  ``--doctest-glob='*.md'`` (pyproject.toml) and left alone here; so are indented blocks, which
  in these pages are formulas.
- A page's blocks form one script, ``python -u PAGE.py`` in the scratch directory: its Python
  blocks pasted verbatim at the top level, in order (a later block uses an earlier one's
  names), and each bash block a call that runs it with ``bash -c`` under ``set -e -o
  pipefail``. The script runs as ``__main__``, as a reader's file would, so code that starts
  a process pool (whose workers import the main script again) must sit under
  ``if __name__ == "__main__":`` in the page too; the bash calls do, so that a worker never
  runs a page's commands again.
- The scratch directory holds a copy of ``examples/`` (what the pages name by relative path);
  ``out/...`` lands in it. ``visviva`` on its ``PATH`` is ``python -m visviva`` of the package
  under test. Numba and OpenBLAS run one thread each (results do not depend on it): the
  suite's other worker holds the other core, and a thread that waits for a busy core made
  the deformables page's projected Newton cloth several times slower.
- Install commands are not run: the snippets run in the environment the suite runs in (CI
  installs the project with its ``test`` extra). In a bash block, a line's leading commands
  joined by ``&&`` that make or enter a virtual environment (``python3 -m venv DIR``,
  ``. DIR/bin/activate``, ``source DIR/bin/activate``) or install with pip (``pip install
  ...``, ``python -m pip install ...``) are dropped, and so is a line of nothing else; the
  README's ``python3 -m venv .venv && . .venv/bin/activate && pip install -e . && visviva demo
  oscillator -o out/oscillator`` runs ``visviva demo oscillator -o out/oscillator``.

Markers, HTML comments that a rendered page does not show:

- ``<!-- snippet: skip — REASON -->`` on the line above a block: not run. The reason is
  required; a skip is for what cannot run in CI (a cluster, a batch system, Node.js).
- ``<!-- snippet: setup`` ... ``-->``: hidden Python run at its place in the page, to complete
  the block after it, which must be marked ``<!-- snippet: fragment -->`` (the line above its
  fence): a block that does not stand on its own and what it stands on. A fragment needs a
  setup or blocks before it.

A failing script's traceback and the failing bash command are reported at the page's lines.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import visviva

#: Fence tags whose blocks run.
RUNNABLE = ("python", "bash")
#: Folders of the repository that the pages name by relative paths, copied into the scratch
#: directory (a copy, so that nothing a page does can write into the repository).
COPIED = ("examples",)
#: A generous bound for one page: a snippet that hangs fails instead of holding CI.
TIMEOUT_S = 900

_TRACEBACK = "Traceback (most recent call last)"
_FENCE = re.compile(r"^```\s*([\w+-]*)\s*$")
_MARKER = re.compile(r"^<!--\s*snippet:\s*(\w+)(.*?)\s*(-->)?\s*$")
_INSTALL = re.compile(
    r"^(python3? -m venv \S+|(\.|source) \S+/bin/activate|(python3? -m )?pip install\b.*)$"
)


class SnippetError(ValueError):
    """A page whose markers are wrong; the message names the page and the line."""


@dataclass(frozen=True)
class Block:
    """A piece of a page's script: a ``python`` or ``bash`` block, or a hidden ``setup``."""

    page: str  # as named in reports, e.g. "docs/sweeps.md"
    line: int  # the page's line of the code's first line (1-based)
    kind: str  # "python", "bash" or "setup"
    code: str
    skip: str | None = None  # why it is not run
    fragment: bool = False


def read_blocks(text: str, page: str) -> list[Block]:
    """The blocks of a page that this runner concerns, in page order; raises
    :class:`SnippetError` for a marker that is malformed or out of place."""
    lines = text.splitlines()
    blocks: list[Block] = []
    pending: list[tuple[int, str, str]] = []  # (line, directive, argument) above the next fence
    i = 0
    while i < len(lines):
        number, line = i + 1, lines[i]
        fence = _FENCE.match(line)
        if fence:
            end = _closing_fence(lines, i, page)
            block = _block(page, number + 1, fence.group(1), lines[i + 1 : end], pending)
            if block is not None:
                blocks.append(block)
            pending = []
            i = end + 1
            continue
        marker = _MARKER.match(line)
        if marker:
            directive, argument, closed = marker.groups()
            if directive == "setup" and not argument and not closed:
                if pending:
                    raise SnippetError(f"{page}:{pending[0][0]}: a marker above a setup")
                end = _closing_comment(lines, i, page)
                blocks.append(Block(page, number + 1, "setup", "\n".join(lines[i + 1 : end])))
                i = end + 1
                continue
            if directive not in ("skip", "fragment") or not closed:
                raise SnippetError(
                    f"{page}:{number}: unknown snippet marker {line.strip()!r}; "
                    "the markers are `<!-- snippet: skip — REASON -->`, "
                    "`<!-- snippet: fragment -->` and `<!-- snippet: setup ... -->`"
                )
            pending.append((number, directive, argument.strip().lstrip("—–-:").strip()))
        elif line.strip() and pending:
            raise SnippetError(f"{page}:{pending[0][0]}: a snippet marker not above a code block")
        i += 1
    if pending:
        raise SnippetError(f"{page}:{pending[0][0]}: a snippet marker not above a code block")
    _check_order(blocks)
    return blocks


def _closing_fence(lines: list[str], start: int, page: str) -> int:
    for end in range(start + 1, len(lines)):
        if lines[end].strip() == "```":
            return end
    raise SnippetError(f"{page}:{start + 1}: a code block that is never closed")


def _closing_comment(lines: list[str], start: int, page: str) -> int:
    for end in range(start + 1, len(lines)):
        if lines[end].strip() == "-->":
            return end
    raise SnippetError(f"{page}:{start + 1}: a setup without its closing `-->` line")


def _block(
    page: str, line: int, tag: str, code: list[str], markers: list[tuple[int, str, str]]
) -> Block | None:
    """The block of a fence, or None for one this runner does not run (and must not mark)."""
    doctest = tag == "python" and next((c for c in code if c.strip()), "").startswith(">>>")
    if tag not in RUNNABLE or doctest:
        if markers:
            what = "a doctest" if doctest else f"a {tag or 'plain'} block, which is not run"
            raise SnippetError(f"{page}:{markers[0][0]}: a snippet marker above {what}")
        return None
    skip, fragment = None, False
    for number, directive, argument in markers:
        if directive == "skip":
            if not argument:
                raise SnippetError(
                    f"{page}:{number}: a skip needs its reason: `<!-- snippet: skip — REASON -->`"
                )
            skip = argument
        else:
            fragment = True
    return Block(page, line, tag, "\n".join(code), skip, fragment)


def _check_order(blocks: list[Block]) -> None:
    """A setup completes the fragment right after it; a fragment has something before it."""
    for k, block in enumerate(blocks):
        if block.kind == "setup":
            after = blocks[k + 1] if k + 1 < len(blocks) else None
            if after is None or not after.fragment or after.skip:
                raise SnippetError(
                    f"{block.page}:{block.line}: a setup must be followed by the block it "
                    "completes, marked `<!-- snippet: fragment -->`"
                )
        if block.fragment and not any(b.skip is None for b in blocks[:k]):
            raise SnippetError(
                f"{block.page}:{block.line}: a fragment with no setup or block before it"
            )


def without_install(code: str) -> str:
    """A bash block without its install commands (see the module's docstring); dropped lines
    stay as empty lines, so that line numbers hold."""
    kept = []
    for line in code.splitlines():
        commands = line.split(" && ")
        while commands and _INSTALL.match(commands[0].strip()):
            commands.pop(0)
        kept.append(" && ".join(commands))
    return "\n".join(kept)


_SCRIPT_HEADER = '''\
import subprocess as _snippet_subprocess
import sys as _snippet_sys


def _snippet_bash(code, page, line):
    """Run a bash block of ``page`` whose first line is ``line``; stop the page at a failure,
    naming the failing command and its line."""
    prelude = (
        "set -e -o pipefail; trap 'status=$?; echo \\"%s:$((LINENO + %d)): exit status "
        "$status: $BASH_COMMAND\\" >&2' ERR" % (page, line - 2)
    )
    status = _snippet_subprocess.run(["bash", "-c", prelude + "\\n" + code]).returncode
    if status:
        _snippet_sys.exit(status)
'''


@dataclass(frozen=True)
class Script:
    """A page's script and, for each of its lines, the page's line it came from."""

    text: str
    origin: list[int | None]


def page_script(blocks: list[Block]) -> Script:
    """The script of a page's blocks (skipped blocks left out, as comments)."""
    lines = _SCRIPT_HEADER.splitlines()
    origin: list[int | None] = [None] * len(lines)
    for k, block in enumerate(blocks, 1):
        where = f"{block.page}:{block.line}"
        lines.append("")
        origin.append(None)
        if block.skip:
            lines.append(f"# block {k}: {where} ({block.kind}), skipped: {block.skip}")
            origin.append(None)
            continue
        lines.append(f"# block {k}: {where} ({block.kind})")
        origin.append(None)
        if block.kind == "bash":
            code = without_install(block.code)
            lines.append('if __name__ == "__main__":  # not again in a process pool\'s workers')
            lines.append(f"    _snippet_bash({code!r}, {block.page!r}, {block.line})")
            origin.extend([block.line, block.line])
        else:
            code_lines = block.code.splitlines()
            lines.extend(code_lines)
            origin.extend(range(block.line, block.line + len(code_lines)))
    return Script("\n".join(lines) + "\n", origin)


@dataclass(frozen=True)
class Outcome:
    """A page's run: its exit status, its output with the script's lines named by the
    page's, and its wall time."""

    page: str
    status: int
    output: str
    seconds: float

    @property
    def passed(self) -> bool:
        """Exit status 0 and no traceback: a traceback printed by a process that did not stop
        the page is a failure too (a process pool's worker that could not start, which a
        sweep reports as failed runs and goes on)."""
        return self.status == 0 and _TRACEBACK not in self.output

    def report(self, shown: int = 80) -> str:
        """The end of the output, or from the first traceback of a page that went on."""
        lines = self.output.splitlines()
        if self.status == 0:
            start = next((k for k, line in enumerate(lines) if _TRACEBACK in line), 0)
            lines = lines[start : start + shown]
        text = "\n".join(lines[-shown:])
        return f"{self.page}: the page's code failed (exit status {self.status}):\n{text}"


def run_page(path: Path, page: str, scratch: Path, root: Path) -> Outcome:
    """Run the blocks of the page at ``path`` (named ``page``) in ``scratch``, with the
    folders :data:`COPIED` copied there from ``root``."""
    blocks = read_blocks(path.read_text(encoding="utf-8"), page)
    script = page_script(blocks)
    work, tools = scratch / "work", scratch / "runner"
    work.mkdir()
    tools.mkdir()
    for name in COPIED:
        shutil.copytree(root / name, work / name)
    program = tools / (Path(page).stem + ".py")
    program.write_text(script.text, encoding="utf-8")
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-u", str(program)],
        cwd=work,
        env=_environment(tools),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=TIMEOUT_S,
    )
    seconds = time.perf_counter() - started
    return Outcome(page, done.returncode, _page_lines(done.stdout, program, page, script), seconds)


def _environment(tools: Path) -> dict[str, str]:
    """The scratch directory's environment: ``visviva`` runs the package under test."""
    shim = tools / "visviva"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m visviva "$@"\n', encoding="utf-8")
    shim.chmod(0o755)
    package_root = str(Path(visviva.__file__).resolve().parents[1])
    path = [str(tools), str(Path(sys.executable).parent), os.environ.get("PATH", "")]
    python_path = [package_root, os.environ.get("PYTHONPATH", "")]
    return os.environ | {
        "PATH": os.pathsep.join(p for p in path if p),
        "PYTHONPATH": os.pathsep.join(p for p in python_path if p),
        "MPLBACKEND": "Agg",
        "NUMBA_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
    }


def _page_lines(output: str, program: Path, page: str, script: Script) -> str:
    """``output`` with each traceback line of the script named by the page's line."""

    def name(match: re.Match[str]) -> str:
        number = int(match.group(1))
        line = script.origin[number - 1] if 0 < number <= len(script.origin) else None
        return f'File "{page}", line {line}' if line else match.group(0)

    return re.sub(rf'File "{re.escape(str(program))}", line (\d+)', name, output)
