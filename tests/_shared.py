"""The project's shared data beside the repository (``../shared``, as in CI): FRET's vectors,
the case-study corpus and the real logs. A user's clone has none; every test that reads it
skips then, with one reason (:data:`REASON`).

* tests that read it while they run take the ``shared`` fixture (``tests/conftest.py``),
  which is this :data:`SHARED` folder or a skip;
* modules that read it at import or collection time load it with :func:`jsonl` (empty when
  the folder is absent) and mark the tests built from it with :data:`needs_shared`.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
PRESENT = SHARED.is_dir()
REASON = ("../shared is absent: FRET's vectors, corpus and real logs come with the project's "
          "shared data")

#: skip marker of the tests that need ../shared
needs_shared = pytest.mark.skipif(not PRESENT, reason=REASON)


def jsonl(relative: str) -> list:
    """The JSON lines of ``../shared/<relative>``; ``[]`` when ../shared is absent."""
    if not PRESENT:
        return []
    with (SHARED / relative).open() as f:
        return [json.loads(line) for line in f if line.strip()]


def skip_without_shared() -> None:
    """Skip the calling test (with :data:`REASON`) when ../shared is absent."""
    if not PRESENT:
        pytest.skip(REASON)


def params(make, arity: int = 1) -> list:
    """Test parameters read from ../shared: ``make()`` when it is present, else one skipped
    placeholder (``arity`` Nones) so that the run says what it leaves out."""
    if PRESENT:
        return list(make())
    return [pytest.param(*[None] * arity, marks=needs_shared, id="shared-absent")]


def cli(*args) -> tuple[int, str]:
    """``fretc *args`` run in process (exceptions raised): (exit code, output)."""
    from click.testing import CliRunner

    from fretc.cli import main

    r = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return r.exit_code, r.output


#: why a test of a live ROS 2 graph is skipped: rclpy (or cyclonedds) is not installed
RCLPY_MISSING = ("ROS 2 Jazzy's rclpy is not installed here (the ros-jazzy-* wheels of the "
                 "test extra are for CPython 3.11 on Linux x86_64)")
CYCLONEDDS_MISSING = "cyclonedds is not installed: pip install 'fretc[watch]'"
