"""A rosbag2 sqlite3 bag is read as evidence: opened read-only and immutable, so auditing it
writes nothing beside the ``.db3`` (a bag in SQLite's WAL journal mode, as rosbag2's
``resilient`` preset writes it, got ``-shm`` and ``-wal`` files beside it), and a bag on
read-only media audits with the verdicts of a writable copy. SQLite's URI
parameters: ``mode=ro``, and ``immutable=1`` ("the database file cannot be changed ... no
locking and no change detection", sqlite.org/uri.html)."""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from _shared import SHARED, needs_shared

ROOT = Path(__file__).resolve().parents[2]
BAG = SHARED / "data" / "foreign_logs" / "rosbag2_services" / "topics_and_services_db3"
FRET = ("W1: the server shall always satisfy wait <= 0.001\n"
        "C: upon req the server shall within 3 ticks satisfy resp\n")
BINDINGS = ('[tick]\nperiod = "100 us"\n[variables]\nwait = "waiting(/add_two_ints)"\n'
            'req = "called(/add_two_ints)"\nresp = "answered(/add_two_ints)"\n')


def _wal_copy(folder: Path) -> Path:
    """A copy of the shared bag's folder in ``folder`` with its ``metadata.yaml`` (a rosbag2
    folder), its database in WAL journal mode."""
    from fretc.logs.ros.rosbag2_storage import _metadata

    bag = folder / "bag"
    shutil.copytree(BAG, bag)
    for p in [bag, *bag.iterdir()]:
        p.chmod(p.stat().st_mode | stat.S_IWUSR)
    db = bag / "topics_and_services.db3"
    (bag / "metadata.yaml").write_text(_metadata(db, db.name), encoding="utf-8")
    con = sqlite3.connect(db)
    try:
        assert con.execute("PRAGMA journal_mode=WAL").fetchone() == ("wal",)
    finally:
        con.close()
    return bag


def _audit(folder: Path, target: Path, wrap: list[str] | None = None) -> dict:
    """``fretc audit --json`` of ``target`` with the requirements in ``folder`` (the cache
    off); the audit JSON's verdicts by requirement. ``wrap``: a command the child is started
    through (a read-only mount, :func:`_read_only_media`)."""
    out = Path(tempfile.mkdtemp(prefix="fretc-ro-out-"))
    env = dict(os.environ, FRETC_CACHE_DIR="")
    got = subprocess.run(
        [*(wrap or []), sys.executable, "-m", "fretc", "audit", "-r", str(folder / "s.fret"),
         "-b", str(folder / "s.bindings.toml"), str(target), "--json", str(out / "a.json"),
         "--no-progress"], cwd=ROOT, capture_output=True, text=True, env=env, timeout=600)
    try:
        assert got.returncode in (0, 1), got.stdout + got.stderr
        doc = json.loads((out / "a.json").read_text(encoding="utf-8"))
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return {v["requirement"]: v["verdict"] for log in doc["logs"] for v in log["verdicts"]}


def _read_only_media(bag: Path, mount: Path) -> list[str] | None:
    """A command prefix that runs its command where ``mount`` holds a copy of ``bag`` on a
    read-only file system (a tmpfs remounted read-only in a mount namespace of its own:
    ``unshare -m``, as root), or None when none can be made here."""
    script = ('mount -t tmpfs none "$1" && cp -a "$2"/. "$1"/ && mount -o remount,ro "$1" '
              '&& ! touch "$1/probe" 2>/dev/null && shift 2 && exec "$@"')
    wrap = ["unshare", "-m", "sh", "-c", script, "sh", str(mount), str(bag)]
    if shutil.which("unshare") is None or subprocess.run(
            [*wrap, "true"], capture_output=True).returncode != 0:
        return None
    return wrap


@needs_shared
@pytest.mark.parametrize("given", ["folder", "storage file alone"])
def test_auditing_a_wal_bag_writes_nothing_beside_it(tmp_path, given):
    bag = _wal_copy(tmp_path)
    (tmp_path / "s.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "s.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    before = sorted(p.name for p in bag.iterdir())
    target = bag if given == "folder" else bag / "topics_and_services.db3"
    verdicts = _audit(tmp_path, target)
    assert set(verdicts) == {"W1", "C"}
    assert sorted(p.name for p in bag.iterdir()) == before == ["metadata.yaml",
                                                                "topics_and_services.db3"]


@pytest.mark.tor("TOR-LOG-001")
@needs_shared
@pytest.mark.parametrize("given", ["folder", "storage file alone"])
def test_a_bag_on_read_only_media_audits_with_the_same_verdicts(tmp_path, given):
    """The WAL bag on a read-only file system (a read-only tmpfs as root; a folder of mode
    0555 and a file of 0444 otherwise): the verdicts of the writable copy."""
    bag = _wal_copy(tmp_path)
    (tmp_path / "s.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "s.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    name = "" if given == "folder" else "topics_and_services.db3"
    pristine = tmp_path / "pristine"  # (as recorded: what the writable audit leaves aside)
    shutil.copytree(bag, pristine)
    writable = _audit(tmp_path, bag / name if name else bag)
    if getattr(os, "geteuid", lambda: 1)() == 0:  # (root writes a folder whatever its mode)
        mount = tmp_path / "media"
        mount.mkdir()
        wrap = _read_only_media(pristine, mount)
        if wrap is None:
            pytest.skip("no read-only file system can be made here (unshare -m, mount)")
        got = _audit(tmp_path, mount / name if name else mount, wrap)
    else:
        for p in pristine.iterdir():
            p.chmod(0o444)
        pristine.chmod(0o555)
        try:
            got = _audit(tmp_path, pristine / name if name else pristine)
        finally:
            pristine.chmod(0o755)
    assert got == writable
