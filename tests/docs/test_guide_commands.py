"""Every command of the user guide runs as written, from the clone's top.

The pages of ``docs/guide/`` (the tour has its own test, tests/docs/test_tour.py, which also
compares what the commands print) and ``docs/bindings.md`` are read with markdown-it (as a
Markdown renderer reads them: fenced blocks and indented blocks, in lists too). A code block
is a *command block* when a line of it starts with ``fretc`` or ``python -m fretc`` (after a
``$ `` prompt, if any; a line ending in ``\\`` continues on the next); its other lines are
what the commands print and are not compared here.

A command block runs unless the line just before it is an HTML comment
``<!-- not run: REASON -->``: the reason is the skip's (a synopsis with optional parts, a
robot's address, a user's own files, a live transport tested in tests/live/). The blocks of
a page run in order, with bash, in one temporary folder that holds copies of the clone's
``requirements/`` and ``traces/`` (commands write there) and links to its other folders,
with this interpreter's ``bin`` folder first on ``PATH``. A command passes when it exits
with a verdict's code (0, 1 or 3: the shipped runs hold violations and unknown verdicts) or
the code a trailing ``# exit code N`` gives, and prints no traceback. The pages whose
commands take minutes (``SLOW_PAGES``) run with ``-m slow``.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted(p for p in (ROOT / "docs" / "guide").glob("*.md") if p.name != "tour.md")
PAGES.append(ROOT / "docs" / "bindings.md")
COPIED = ("requirements", "traces")
LINKED = ("sim", "bench", "tests", "docs", "templates", "monitors")
_COMMAND = re.compile(r"^(fretc\b|python3? -m fretc\b)")
_EXIT = re.compile(r"\s+#\s*exit code (\d+)\s*$")
_NOT_RUN = re.compile(r"<!--\s*not run:\s*(.+?)\s*-->", re.S)
VERDICT_CODES = (0, 1, 3)


@dataclass
class Block:
    """One command block: its page line (1-based), commands, and why it is not run."""

    line: int
    commands: list[tuple[str, int | None]]
    not_run: str | None


def _joined(lines: list[str]) -> list[str]:
    out: list[str] = []
    cont = False
    for raw in lines:
        line = raw.rstrip()
        if line.startswith("$ "):
            line = line[2:]
        if cont:
            out[-1] = out[-1][:-1].rstrip() + " " + line.strip()
        else:
            out.append(line.strip())
        cont = out[-1].endswith("\\")
    return out


def command_blocks(text: str) -> list[Block]:
    """The command blocks of a page (module docstring), in order."""
    tokens = MarkdownIt("commonmark").parse(text)
    blocks: list[Block] = []
    previous = None
    for tok in tokens:
        if tok.type in ("fence", "code_block") and tok.map is not None:
            lang = tok.info.strip().split()[0] if tok.info.strip() else ""
            if lang in ("", "console", "sh", "bash", "shell"):
                commands = []
                for line in _joined(tok.content.splitlines()):
                    if _COMMAND.match(line):
                        m = _EXIT.search(line)
                        code = int(m.group(1)) if m else None
                        commands.append((_EXIT.sub("", line), code))
                if commands:
                    why = None
                    if previous is not None and previous.type == "html_block":
                        m = _NOT_RUN.search(previous.content)
                        why = m.group(1) if m else None
                    blocks.append(Block(tok.map[0] + 1, commands, why))
        if tok.type not in ("paragraph_close", "list_item_open", "bullet_list_open",
                            "ordered_list_open"):
            previous = tok
    return blocks


def _workspace(folder: Path) -> dict:
    for name in COPIED:
        shutil.copytree(ROOT / name, folder / name, symlinks=True)
    for name in LINKED:
        (folder / name).symlink_to(ROOT / name, target_is_directory=True)
    return dict(os.environ, PATH=os.pathsep.join([str(Path(sys.executable).parent),
                                                 os.environ.get("PATH", "")]),
                PYTHONHASHSEED="0")


# pages whose commands take tens of seconds to minutes of CPU (falsify searches, statistical
# runs, generated test suites run): in the slow part of the suite, as one test (a
# parametrized slow test keeps a sample of its cases in the default run)
SLOW_PAGES = ("falsify.md", "statistics.md", "testing.md")
#: seconds a command of a slow page may take (the falsify page's search of 200 simulator
#: runs takes 300 to 400 s of CPU on the 2-core CI machine), of another page
SLOW_TIMEOUT, TIMEOUT = 900, 300


def _run_page(page: Path, folder: Path) -> None:
    blocks = command_blocks(page.read_text(encoding="utf-8"))
    env = _workspace(folder)
    ran = 0
    for block in blocks:
        if block.not_run is not None:
            continue
        for command, code in block.commands:
            got = subprocess.run(["bash", "-c", command], cwd=folder, env=env,
                                 capture_output=True, text=True,
                                 timeout=SLOW_TIMEOUT if page.name in SLOW_PAGES else TIMEOUT)
            where = f"{page.relative_to(ROOT)}:{block.line}: {command}"
            assert "Traceback (most recent call last)" not in got.stderr, \
                (where, got.stderr[-2000:])
            ok = got.returncode == code if code is not None else \
                got.returncode in VERDICT_CODES
            assert ok, (where, got.returncode, got.stderr[-2000:], got.stdout[-1000:])
            ran += 1
    if not ran:
        reasons = sorted({b.not_run for b in blocks if b.not_run})
        pytest.skip("no command of the page is run as written"
                    + (f": {'; '.join(reasons)}" if reasons else ""))


@pytest.mark.parametrize("page", [p for p in PAGES if p.name not in SLOW_PAGES],
                         ids=lambda p: p.name)
def test_every_command_of_the_page_runs_as_written(page, tmp_path):
    _run_page(page, tmp_path)


@pytest.mark.slow
def test_every_command_of_the_long_pages_runs_as_written(tmp_path):
    for name in SLOW_PAGES:
        folder = tmp_path / name
        folder.mkdir()
        _run_page(ROOT / "docs" / "guide" / name, folder)


def test_the_parser_finds_blocks_in_lists_prompts_continuations_and_markers():
    text = ("Intro\n\n    fretc check requirements/ \\\n      --inputs a\n    output line\n\n"
            "1. an item\n\n        fretc audit -r r.fret x.mcap   # exit code 2\n\n"
            "<!-- not run: a synopsis -->\n```console\n$ fretc watch ws://ROBOT:8765\n```\n"
            "```toml\nfretc = 1\n```\n")
    got = command_blocks(text)
    assert [(b.commands, b.not_run) for b in got] == [
        ([("fretc check requirements/ --inputs a", None)], None),
        ([("fretc audit -r r.fret x.mcap", 2)], None),
        ([("fretc watch ws://ROBOT:8765", None)], "a synopsis")]
