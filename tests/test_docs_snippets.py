"""Every code block of README.md and docs/*.md runs as written (tests/snippets.py says how:
a page's blocks in order in one scratch directory, bash blocks with ``visviva`` of this
checkout, markers for the few that cannot run), so that a snippet cannot rot unseen."""

from __future__ import annotations

from pathlib import Path

import pytest

import snippets

ROOT = Path(__file__).resolve().parents[1]
PAGES = ["README.md", *sorted(p.relative_to(ROOT).as_posix() for p in ROOT.glob("docs/*.md"))]


def _blocks(page: str) -> list[snippets.Block]:
    return snippets.read_blocks((ROOT / page).read_text(encoding="utf-8"), page)


def _runs_code(page: str) -> bool:
    try:
        return any(block.skip is None for block in _blocks(page))
    except snippets.SnippetError:
        return True  # its test fails, naming the marker at fault


WITH_CODE = [page for page in PAGES if _runs_code(page)]


@pytest.mark.parametrize("page", WITH_CODE)
def test_page_runs_as_written(page: str, tmp_path: Path) -> None:
    outcome = snippets.run_page(ROOT / page, page, tmp_path, ROOT)
    print(f"{page}: {outcome.seconds:.1f} s")
    assert outcome.passed, outcome.report()


def test_every_page_has_well_formed_markers() -> None:
    for page in PAGES:
        _blocks(page)  # raises SnippetError, naming the line


def test_the_readme_test_command_is_the_suite_itself() -> None:
    """CI runs it (tests/test_readme.py); run here it would run this test again."""
    test_command = [b for b in _blocks("README.md") if b.kind == "bash"][1]
    assert "python -m pytest" in test_command.code and test_command.skip


# The runner's own rules, on small pages.


def test_blocks_are_read_in_order_with_their_lines_and_markers() -> None:
    page = (
        "Text.\n"
        "```python\nx = 1\n```\n"
        "```python\n>>> 1 + 1\n2\n```\n"  # a doctest: pytest's, not ours
        "```toml\na = 1\n```\n"
        "<!-- snippet: setup\ny = 2\n-->\n"
        "<!-- snippet: fragment -->\n"
        "```bash\necho $y\n```\n"
        "<!-- snippet: skip — needs a cluster -->\n"
        "```bash\nssh head\n```\n"
    )
    blocks = snippets.read_blocks(page, "page.md")
    assert [(b.kind, b.line, b.code) for b in blocks] == [
        ("python", 3, "x = 1"),
        ("setup", 13, "y = 2"),
        ("bash", 17, "echo $y"),
        ("bash", 21, "ssh head"),
    ]
    assert blocks[2].fragment and blocks[3].skip == "needs a cluster"


@pytest.mark.parametrize(
    ("page", "message"),
    [
        ("<!-- snippet: skip -->\n```bash\nls\n```\n", "page.md:1: a skip needs its reason"),
        ("<!-- snippet: sikp — x -->\n```bash\nls\n```\n", "page.md:1: unknown snippet marker"),
        ("<!-- snippet: fragment -->\n\nText.\n```bash\nls\n```\n", "page.md:1: a snippet"),
        ("<!-- snippet: fragment -->\n```bash\nls\n```\n", "page.md:3: a fragment with no"),
        ("```bash\nls\n```\n<!-- snippet: setup\nx = 1\n-->\n```bash\nls\n```\n", "page.md:5"),
        ("<!-- snippet: skip — x -->\n```toml\na = 1\n```\n", "page.md:1: a snippet marker"),
        ("```bash\nls\n", "page.md:1: a code block that is never closed"),
    ],
)
def test_malformed_markers_are_refused_at_their_line(page: str, message: str) -> None:
    with pytest.raises(snippets.SnippetError, match=message):
        snippets.read_blocks(page, "page.md")


def test_install_commands_are_dropped_and_the_rest_kept() -> None:
    block = (
        "python3 -m venv .venv && . .venv/bin/activate && pip install -e . && visviva demo x\n"
        'pip install "visviva[dask]"   # optional\n'
        "visviva run a.toml && pip install later"
    )
    assert snippets.without_install(block).splitlines() == [
        "visviva demo x",
        "",
        "visviva run a.toml && pip install later",
    ]


def test_a_failure_is_reported_at_the_page_line(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("```bash\ntrue\nfalse\n```\n\n```python\nvalue = 1\n```\n", encoding="utf-8")
    outcome = snippets.run_page(page, "page.md", tmp_path, ROOT)
    assert outcome.status == 1 and "page.md:3: exit status 1: false" in outcome.output
    page.write_text("```python\nx = 1\nraise ValueError(x)\n```\n", encoding="utf-8")
    (tmp_path / "again").mkdir()
    outcome = snippets.run_page(page, "page.md", tmp_path / "again", ROOT)
    assert outcome.status == 1 and 'File "page.md", line 3' in outcome.output


def test_a_traceback_fails_a_page_that_went_on() -> None:
    """As when a process pool's workers cannot start: the sweep lists its runs as failed."""
    worker = "Traceback (most recent call last):\n  ...\nRuntimeError: bootstrapping phase"
    assert not snippets.Outcome("page.md", 0, f"ran\n{worker}\n12 runs\n", 1.0).passed
    assert snippets.Outcome("page.md", 0, "12 runs\n", 1.0).passed
