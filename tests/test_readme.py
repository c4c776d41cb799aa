"""The README's promises: CI runs its test command verbatim, and its commands write under out/."""

import re
from pathlib import Path

ROOT = Path(__file__).parents[1]


def _commands() -> list[str]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"```bash\n(.*?)```", readme, re.S)


def test_ci_runs_the_readme_test_command_verbatim():
    install_and_demo, test = (block.strip() for block in _commands()[:2])
    assert "visviva demo" in install_and_demo and "pytest" in test
    assert "tools/install-browser" in test  # a fresh machine gets Chromium from the command
    assert test in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()


def test_readme_commands_write_under_out():
    for block in _commands():
        for target in re.findall(r"(?:-o|--output)\s+(\S+)", block):
            assert target.startswith("out/"), f"{target!r} would land in the repository root"
