"""``docs/guide/shield-replay.md`` shows what its commands print: each ``sh`` block that a
``text`` block follows, run in order from one folder holding the clone's ``requirements/``
and ``traces/`` (links), with this interpreter's ``bin`` folder first on ``PATH``, and the
``text`` block compared line by line with the block's last command's output (runs of spaces
not compared: the audit's table pads to the terminal's width)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "shield-replay.md"
_EXIT = re.compile(r"\s+#\s*exit code (\d+)\s*$")


def _squeezed(line: str) -> str:
    return " ".join(line.split())


def test_the_page_shows_what_the_replay_prints(tmp_path):
    text = PAGE.read_text(encoding="utf-8")
    pairs = re.findall(r"```sh\n(.*?)```\s*```text\n(.*?)```", text, re.S)
    assert len(pairs) >= 2  # (the whole run, a damaged copy of it)
    for name in ("requirements", "traces"):
        (tmp_path / name).symlink_to(ROOT / name)
    env = {**os.environ, "PATH": str(Path(sys.executable).parent) + os.pathsep
           + os.environ.get("PATH", ""), "COLUMNS": "160"}
    for commands, shown in pairs:
        _check_block(commands, shown, tmp_path, env)


def _check_block(commands: str, shown: str, folder: Path, env: dict) -> None:
    """Run the block's ``commands`` in ``folder``; its last one prints ``shown``."""
    lines = commands.replace("\\\n", " ").splitlines()
    *before, last = [line.strip() for line in lines if line.strip()]
    m = _EXIT.search(last)
    code = int(m.group(1)) if m else 0
    last = _EXIT.sub("", last)
    for command in before:
        done = subprocess.run(["bash", "-c", command], cwd=folder, env=env,
                              capture_output=True, text=True)
        assert done.returncode == 0, (command, done.stdout, done.stderr)
    done = subprocess.run(["bash", "-c", last], cwd=folder, env=env, capture_output=True,
                          text=True)
    assert done.returncode == code, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr
    printed = [_squeezed(line) for line in done.stdout.splitlines()]
    assert printed == [_squeezed(line) for line in shown.splitlines()]
