"""A log that is a stream, not a file (hostile round 9): a FIFO, ``/dev/stdin``, a
shell's ``<(...)`` (``/dev/fd/N``). ``fretc audit`` ended in an internal error
(NotADirectoryError) and ``fretc shield-replay`` in "not seekable"; both now refuse it
before reading a byte, exit 2, naming the path (fretc reads a log more than once and out of
order, which a stream cannot give)."""

from __future__ import annotations

import os
import sys
import threading
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main

CSV = b"time,x\n0,1\n1,2\n"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


class _Writer:
    """A thread writing ``data`` into the FIFO ``path`` (it blocks until a reader opens
    it); :meth:`close` unblocks and joins it whether or not anything read it."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path = path
        self.thread = threading.Thread(target=self._write, args=(data,), daemon=True)
        self.thread.start()

    def _write(self, data: bytes) -> None:
        try:
            with open(self.path, "wb") as f:
                f.write(data)
        except OSError:
            pass

    def close(self) -> None:
        fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)  # (the writer's open returns)
        try:
            self.thread.join(5)
            while os.read(fd, 65536):
                pass
        except BlockingIOError:
            pass
        finally:
            os.close(fd)
        self.thread.join(5)
        assert not self.thread.is_alive()


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "run.csv"
    os.mkfifo(path)
    (tmp_path / "r.fret").write_text("R: the robot shall always satisfy x > 0\n")
    w = _Writer(path, CSV)
    yield path
    w.close()


def test_audit_of_a_fifo_is_refused_naming_it(fifo):
    got = _run("audit", fifo, "-r", fifo.parent / "r.fret")
    assert got.exit_code == 2, got.output
    assert str(fifo) in got.output and "FIFO" in got.output
    assert "internal error" not in got.output and "Traceback" not in got.output


def test_audit_of_a_fifo_inside_a_folder_searched_is_refused(fifo):
    """Named by a folder search (the FIFO's suffix is a log's): refused as well, by the
    reader (open_log), never an internal error."""
    got = _run("audit", fifo.parent, "-r", fifo.parent / "r.fret")
    assert got.exit_code == 2, got.output
    assert "run.csv" in got.output and "internal error" not in got.output


def test_audit_of_dev_fd_n_is_refused(tmp_path):
    """A shell's <(...) is /dev/fd/N, a pipe."""
    (tmp_path / "r.fret").write_text("R: the robot shall always satisfy x > 0\n")
    r, w = os.pipe()
    try:
        os.write(w, CSV)
        os.close(w)
        got = _run("audit", f"/dev/fd/{r}", "-r", tmp_path / "r.fret")
    finally:
        os.close(r)
    assert got.exit_code == 2, got.output
    assert f"/dev/fd/{r}" in got.output and "internal error" not in got.output


def test_shield_replay_of_a_fifo_is_refused_naming_it(tmp_path_factory, tmp_path):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "shield"))
    from _replay import REPO, TRACE, docs_shield

    shield = docs_shield(tmp_path_factory.mktemp("shield"))
    path = tmp_path / "run.mcap"
    os.mkfifo(path)
    w = _Writer(path, TRACE.read_bytes())
    try:
        got = _run("shield-replay", shield, path, "-o", tmp_path / "out", "-r",
                   REPO / "requirements" / "safe_ros.fret")
    finally:
        w.close()
    assert got.exit_code == 2, got.output
    assert str(path) in got.output and "FIFO" in got.output
    assert "not seekable" not in got.output and "internal error" not in got.output


def test_the_check_names_the_kind_and_passes_files_and_folders(tmp_path):
    from fretc.logs.factory import unseekable

    (tmp_path / "a.csv").write_bytes(CSV)
    os.mkfifo(tmp_path / "p")
    assert unseekable(tmp_path / "a.csv") is None and unseekable(tmp_path) is None
    assert unseekable(tmp_path / "missing") is None
    assert "FIFO" in unseekable(tmp_path / "p")
    (tmp_path / "l").symlink_to(tmp_path / "p")
    assert "FIFO" in unseekable(tmp_path / "l")
    if os.path.exists("/dev/null"):
        assert "character device" in unseekable("/dev/null")
