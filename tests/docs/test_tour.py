"""The user guide's tour (``docs/guide/tour.md``) runs as written, on the shipped traces.

Every ``console`` block of the page is read as the page explains it: a line starting with
``$ `` is a command, the lines after it are what it prints (an excerpt: ``...`` stands for
lines left out). A command ending in ``&`` is started in the background (the simulator's
server) and stopped when the module ends; a trailing ``# exit code N`` comment gives the
exit code (0 when there is none). The commands run in order, with bash, in a temporary
folder holding ``requirements/`` and ``traces/`` (links to the clone's), with this
interpreter's ``bin`` folder first on ``PATH`` (``fretc`` and ``python`` are the installed
ones). A shown line must be printed (on stdout or stderr) with the same words; runs of
spaces are not compared (terminal tables pad to the terminal's width).

The audit's ``--json`` document written by the tour is also validated against the JSON
Schema of the docs (``docs/reference/audit.schema.json``).
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "guide" / "tour.md"
SCHEMA = ROOT / "docs" / "reference" / "audit.schema.json"

pytestmark = pytest.mark.xdist_group("docs_tour")

_EXIT = re.compile(r"\s+#\s*exit code (\d+)\s*$")


@dataclass
class Step:
    """One command of the page and the output lines it shows."""

    command: str
    shown: list[str] = field(default_factory=list)
    exit_code: int = 0
    background: bool = False


def tour_steps(text: str) -> list[Step]:
    """The commands of the page's ``console`` blocks, in order."""
    steps: list[Step] = []
    for block in re.findall(r"```console\n(.*?)```", text, re.S):
        for line in block.splitlines():
            if line.startswith("$ "):
                cmd = line[2:].strip()
                m = _EXIT.search(cmd)
                code = int(m.group(1)) if m else 0
                cmd = _EXIT.sub("", cmd)
                bg = cmd.endswith("&")
                steps.append(Step(cmd.rstrip("&").strip(), [], code, bg))
            elif steps and line.strip() and line.strip() != "...":
                steps[-1].shown.append(line)
    return steps


STEPS = tour_steps(PAGE.read_text(encoding="utf-8"))


def _words(line: str) -> str:
    return " ".join(line.split())


class Tour:
    """Runs the page's commands in order, each once, on first need."""

    def __init__(self, folder: Path):
        self.folder = folder
        for name in ("requirements", "traces"):
            (folder / name).symlink_to(ROOT / name, target_is_directory=True)
        self.env = dict(os.environ, PATH=os.pathsep.join(
            [str(Path(sys.executable).parent), os.environ.get("PATH", "")]))
        self.results: list[subprocess.CompletedProcess | None] = []
        self.background: list[subprocess.Popen] = []

    def result(self, index: int) -> subprocess.CompletedProcess | None:
        while len(self.results) <= index:
            self.results.append(self._run(STEPS[len(self.results)]))
        return self.results[index]

    def _run(self, step: Step) -> subprocess.CompletedProcess | None:
        if step.background:
            self.background.append(subprocess.Popen(
                ["bash", "-c", "exec " + step.command], cwd=self.folder, env=self.env,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            return None
        return subprocess.run(["bash", "-c", step.command], cwd=self.folder, env=self.env,
                              capture_output=True, text=True, timeout=600)

    def close(self) -> None:
        for proc in self.background:
            if proc.poll() is None:
                proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


@pytest.fixture(scope="module")
def tour(tmp_path_factory):
    t = Tour(tmp_path_factory.mktemp("tour"))
    yield t
    t.close()


def test_the_page_has_the_tour():
    """The parse finds the tour's steps: formalize, explain, simulate, emit, audit, report,
    check, watch; every step shows what it prints (but a step writing a file)."""
    commands = [s.command for s in STEPS]
    for start in ("fretc requirements/r1.fret --emit ltl", "fretc explain", "fretc simulate",
                  "fretc requirements/r1.fret --emit monitor", "fretc audit", "fretc report",
                  "fretc check", "python -m fretc.sim serve", "fretc watch"):
        assert any(c.startswith(start) for c in commands), start
    assert all(s.shown or " > " in s.command for s in STEPS if not s.background)


def _marks(step: Step):
    return [pytest.mark.watch] if ("sim serve" in step.command or "watch" in step.command) else []


@pytest.mark.parametrize("index", [pytest.param(i, id=f"{i}-{s.command.split()[0]}-{s.command.split()[1]}",
                                                marks=_marks(s))
                                   for i, s in enumerate(STEPS) if not s.background])
def test_tour_command_prints_what_the_page_shows(tour, index):
    step = STEPS[index]
    res = tour.result(index)
    printed = {_words(line) for line in (res.stdout + "\n" + res.stderr).splitlines()}
    missing = [line for line in step.shown if _words(line) not in printed]
    assert not missing, (step.command, missing, res.stdout[-3000:], res.stderr[-3000:])
    assert res.returncode == step.exit_code, (step.command, res.stderr[-3000:])


def test_audit_json_of_the_main_job_matches_the_schema(tour):
    """The ``--json`` document of the tour's audit (the main job) is valid under the docs'
    JSON Schema, and the schema rejects a document that breaks it."""
    jsonschema = pytest.importorskip("jsonschema")
    index = next(i for i, s in enumerate(STEPS) if s.command.startswith("fretc audit"))
    assert "--json audit.json" in STEPS[index].command
    assert tour.result(index).returncode == 1
    doc = json.loads((tour.folder / "audit.json").read_text(encoding="utf-8"))
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    jsonschema.Draft202012Validator.check_schema(schema)
    errors = [e.message for e in validator.iter_errors(doc)]
    assert not errors, errors[:5]
    assert doc["summary"]["violated"] == 7

    broken = json.loads(json.dumps(doc))
    broken["logs"][0]["verdicts"][0]["verdict"] = "maybe"
    del broken["summary"]["exit_code"]
    messages = " ".join(e.message for e in validator.iter_errors(broken))
    assert "'maybe' is not one of" in messages and "'exit_code' is a required" in messages
