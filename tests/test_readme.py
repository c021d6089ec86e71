"""The README and the guide, run as a new user would: every ``pvcloth``
command they show on a bundled scene runs as written (in a fresh folder
holding the repository's ``data/``), every subcommand they name answers
``--help``, every subcommand of the program is documented, and every fenced
``python`` block runs. The guide is every Markdown page of ``docs/`` (what
the build generates aside).

The commands go through the console script, the documented path, not the
Python functions behind it. ``pvcloth run`` needs a screen: it is run as a
person would in ``tests/test_run_command.py``.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT
from pvcloth.cli import build_parser

README = (ROOT / "README.md").read_text(encoding="utf-8")
#: The pages a user reads, by their path in the repository.
GENERATED = ("docs/_build", "docs/api", "docs/auto_examples", "docs/performance/results")
PAGES = {
    "README.md": README,
    **{
        str(path.relative_to(ROOT)): path.read_text(encoding="utf-8")
        for path in sorted((ROOT / "docs").rglob("*.md"))
        if not str(path.relative_to(ROOT)).startswith(GENERATED)
    },
}
PVCLOTH = str(Path(sys.executable).with_name("pvcloth"))


def fenced_blocks(text: str, language: str) -> list[str]:
    """The contents of the ```language fenced blocks of a Markdown text."""
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.S | re.M)


def documented_commands(text: str) -> list[str]:
    """Every ``pvcloth ...`` command: inline code spans, and lines of the
    ``bash`` and ``text`` blocks or their ``&&``-chained parts (``\\``
    continuations joined, ``#`` comments cut)."""
    commands = re.findall(r"`(pvcloth [^`]+)`", text)
    for block in fenced_blocks(text, "bash") + fenced_blocks(text, "text"):
        for line in block.replace("\\\n", " ").splitlines():
            for part in line.split("#")[0].split("&&"):
                if part.strip().startswith("pvcloth "):
                    commands.append(" ".join(part.split()))
    return commands


def _subcommand(command: str) -> str:
    return command.split()[1]


COMMANDS = [command for text in PAGES.values() for command in documented_commands(text)]
#: Commands on real files (the others are templates: SCENE.toml, OUT.gif...),
#: each once.
RUNNABLE = list(
    dict.fromkeys(c for c in COMMANDS if "data/scenes/" in c and _subcommand(c) != "run")
)
#: Every fenced python block, by page and number.
PYTHON = [
    (page, number, code)
    for page, text in PAGES.items()
    for number, code in enumerate(fenced_blocks(text, "python"))
]
#: Commands that take half a minute to minutes as written (a 120-run sweep,
#: every integrator at 8 steps, three panels against an RK4 reference): the
#: validation tier runs them; their quick twins run the same code smaller
#: (test_interrupts' sweep from the console, test_tradeoff's command,
#: test_view's compare).
SLOW = {"sweep", "tradeoff", "compare"}


def subcommands() -> set[str]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.dest == "command"]
    return set(sub.choices)


@pytest.fixture
def user_folder(tmp_path):
    """A fresh folder with the repository's data in it, as after a clone."""
    (tmp_path / "data").symlink_to(ROOT / "data")
    return tmp_path


def test_the_readme_shows_commands_and_python():
    assert len(RUNNABLE) >= 5 and fenced_blocks(README, "python")


def test_ci_runs_the_readme_test_command_as_written():
    """CI (``.ci/run``) runs exactly what the README tells a developer to."""
    (block,) = [b for b in fenced_blocks(README, "bash") if "'.[test]'" in b]
    command = block.strip().split("pip install -e '.[test]' && ")[1]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert command in ci


def test_every_subcommand_is_documented_and_every_documented_one_exists():
    named = {_subcommand(c) for c in COMMANDS if not c.split()[1].startswith("-")}
    assert named == subcommands()


@pytest.mark.parametrize("name", sorted(subcommands()))
def test_every_subcommand_answers_help(name):
    result = subprocess.run([PVCLOTH, name, "--help"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: pvcloth {name}")


def test_version_comes_from_the_package_metadata():
    from importlib.metadata import version

    result = subprocess.run([PVCLOTH, "--version"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0
    assert result.stdout.strip() == f"pvcloth {version('pvcloth')}"


@pytest.mark.usefixtures("rendering")
@pytest.mark.parametrize(
    "command",
    [
        pytest.param(c, marks=pytest.mark.validation) if _subcommand(c) in SLOW else c
        for c in RUNNABLE
    ],
)
def test_readme_command_runs_as_written(command, user_folder):
    result = subprocess.run(
        [PVCLOTH, *shlex.split(command)[1:]],
        cwd=user_folder,
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "Traceback" not in result.stderr
    args = shlex.split(command)
    if "-o" in args:  # what it says it wrote is there
        assert (user_folder / args[args.index("-o") + 1]).exists()


@pytest.mark.usefixtures("rendering")
@pytest.mark.parametrize(
    ("page", "number", "code"), PYTHON, ids=[f"{page}-{number}" for page, number, _ in PYTHON]
)
def test_readme_python_block_runs_as_written(page, number, code, user_folder):
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=user_folder, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr[-2000:]
