"""Output writers never write through a link planted in their output folder:
:mod:`fretc.common.outputs` itself, then each command that writes files, run with a link
``D/NAME -> victim`` planted under every name it writes (a folder it makes, ``runs/`` or
``timelines/``, planted as a link to a victim folder): the victims are unchanged, each file
is written in place of its link, and a link where fretc makes a folder is refused (exit 2,
naming it).

The commands run in child processes (``python -m fretc``) that inherit this process's
environment, so the tests can be run against another tree (``PYTHONPATH=OTHER/src``)."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
R1 = ROOT / "requirements" / "r1.fret"
PRECIOUS = "precious: must not change\n"


# --------------------------------------------------------------------------- the helper
@pytest.fixture
def victim(tmp_path) -> Path:
    v = tmp_path / "victim.txt"
    v.write_text(PRECIOUS)
    return v


@pytest.mark.tor("TOR-OUT-002")
def test_write_file_replaces_a_symbolic_link_never_its_target(tmp_path, victim):
    from fretc.common import outputs

    out = tmp_path / "out.txt"
    out.symlink_to(victim)
    outputs.write_file(out, "new\n")
    assert victim.read_text() == PRECIOUS
    assert not out.is_symlink() and out.read_text() == "new\n"


def test_write_file_replaces_a_hard_link_never_the_other_name(tmp_path, victim):
    from fretc.common import outputs

    out = tmp_path / "out.txt"
    os.link(victim, out)
    outputs.write_file(out, b"new\n")
    assert victim.read_text() == PRECIOUS and out.read_bytes() == b"new\n"


def test_written_files_are_made_as_open_would_and_leave_no_temporary(tmp_path):
    from fretc.common import outputs

    old = os.umask(0o027)
    try:
        outputs.write_file(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


@pytest.mark.tor("TOR-OUT-002")
def test_a_failed_write_keeps_the_old_file_and_no_temporary(tmp_path):
    from fretc.common import outputs

    out = tmp_path / "out.txt"
    out.write_text("old\n")
    with pytest.raises(RuntimeError):
        with outputs.open_output(out) as f:
            f.write("half")
            raise RuntimeError("stopped half-way")
    assert out.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["out.txt"]
    (tmp_path / "dir").mkdir()
    with pytest.raises(outputs.OutputError, match="dir"):
        outputs.write_file(tmp_path / "dir", "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir", "out.txt"]


def test_create_output_removes_a_link_and_creates_exclusively(tmp_path, victim):
    from fretc.common import outputs

    out = tmp_path / "rec.mcap"
    out.symlink_to(victim)
    with outputs.create_output(out) as f:
        f.write(b"new")
    assert victim.read_text() == PRECIOUS and out.read_bytes() == b"new"
    assert not out.is_symlink()


def _device(tmp_path: Path, name: str, minor: int) -> str:
    """The character device ``/dev/NAME`` (major 1, ``minor``) to write to: as root a node of
    its own made in ``tmp_path`` (a broken fretc, or a mutant of the campaign, renaming a file
    over it must not replace the machine's /dev/null), else the machine's (a fault is then a
    permission error). Skips where neither can be had."""
    if os.geteuid() != 0:
        if not os.path.exists(f"/dev/{name}"):
            pytest.skip(f"no /dev/{name} on this system")
        return f"/dev/{name}"
    node = tmp_path / name
    try:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
    except OSError as exc:
        pytest.skip(f"as root, a device of the test's own cannot be made ({exc})")
    return str(node)


@pytest.mark.tor("TOR-OUT-002")
def test_a_device_or_fifo_named_as_the_output_is_written_through_and_stays_one(tmp_path):
    """``-o /dev/null`` discards the output as the shell's ``>`` does: /dev/null stays a
    character device (renaming a temporary file over it made it a regular file when fretc
    ran as root; as any other user it was a permission error). A FIFO named as the output
    gets the bytes; a link to a device is refused (a link planted in a shared folder must
    not make fretc write to a device), naming it."""
    import threading

    from fretc.common import outputs

    null = _device(tmp_path, "null", 3)
    outputs.write_file(null, "discarded\n")
    with outputs.create_output(null) as f:
        f.write(b"discarded")
    assert stat.S_ISCHR(os.lstat(null).st_mode)
    fifo = tmp_path / "p"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    outputs.write_file(fifo, "through the pipe\n")
    reader.join(timeout=30)
    assert got == [b"through the pipe\n"] and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    link = tmp_path / "out.txt"
    link.symlink_to(null)
    with pytest.raises(outputs.OutputError) as err:
        outputs.write_file(link, "x")
    assert str(link) in str(err.value) and "a link to a device" in str(err.value)
    assert link.is_symlink()


def test_sub_folder_refuses_a_link_or_a_file(tmp_path):
    from fretc.common import outputs

    victim_dir = tmp_path / "victim"
    victim_dir.mkdir()
    (tmp_path / "runs").symlink_to(victim_dir)
    with pytest.raises(outputs.OutputError, match="symbolic link"):
        outputs.sub_folder(tmp_path, "runs")
    (tmp_path / "file").write_text("x")
    with pytest.raises(outputs.OutputError, match="not a folder"):
        outputs.sub_folder(tmp_path, "file")
    assert outputs.sub_folder(tmp_path, "new") == str(tmp_path / "new")
    assert outputs.sub_folder(tmp_path, "new") == str(tmp_path / "new")  # (exists: fine)


def test_write_under_makes_its_folders_and_refuses_links_on_the_way(tmp_path, victim):
    from fretc.common import outputs

    victim_dir = tmp_path / "victim"
    victim_dir.mkdir()
    d = tmp_path / "d"
    d.mkdir()
    assert outputs.write_under(d, "pkg/launch/x.py", "x") == str(d / "pkg" / "launch" / "x.py")
    (d / "pkg2").symlink_to(victim_dir)
    with pytest.raises(outputs.OutputError, match="symbolic link"):
        outputs.write_under(d, "pkg2/x.py", "x")
    assert list(victim_dir.iterdir()) == []
    for bad in ("", "/abs", "a/../b", "a//b", "./a"):
        with pytest.raises(ValueError):
            outputs.write_under(d, bad, "x")


# --------------------------------------------------------------------------- each writer
def _fretc(args, cwd=ROOT) -> subprocess.CompletedProcess:
    env = dict(os.environ, COLUMNS="120", NO_COLOR="1")
    return subprocess.run([sys.executable, "-m", "fretc", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=600)


def _victims(tmp_path: Path) -> tuple[Path, Path]:
    victim = tmp_path / "victim.txt"
    victim.write_text(PRECIOUS)
    folder = tmp_path / "victim_dir"
    folder.mkdir()
    (folder / "keep.txt").write_text(PRECIOUS)
    return victim, folder


def _state(folder: Path) -> dict:
    return {p.name: p.read_text() for p in folder.iterdir()}


def _planted(tmp_path: Path, names: list[str], folders: set[str]) -> Path:
    """A folder ``D`` holding a link to the victim under each name of ``names`` (to the
    victim folder for those of ``folders``)."""
    victim, victim_dir = _victims(tmp_path)
    d = tmp_path / "D"
    d.mkdir()
    for name in names:
        (d / name).symlink_to(victim_dir if name in folders else victim)
    return d


def _check(tmp_path: Path, d: Path, got: subprocess.CompletedProcess, files: list[str]) -> None:
    """The victims unchanged; each name of ``files`` written in place of its link."""
    assert (tmp_path / "victim.txt").read_text() == PRECIOUS, got.stderr
    assert _state(tmp_path / "victim_dir") == {"keep.txt": PRECIOUS}, got.stderr
    for name in files:
        assert not (d / name).is_symlink() and (d / name).is_file(), (name, got.stderr)


def _names(folder: Path) -> tuple[list[str], set[str]]:
    names = sorted(p.name for p in folder.iterdir())
    return names, {n for n in names if (folder / n).is_dir()}


def _writes_into(tmp_path: Path, args) -> tuple[Path, subprocess.CompletedProcess, list, set]:
    """Run ``args(folder)`` into a clean folder to learn what it writes, then into a folder
    with a link planted under each of those names."""
    clean = tmp_path / "clean"
    first = _fretc(args(clean))
    names, folders = _names(clean)
    assert names, first.stderr
    d = _planted(tmp_path, names, folders)
    return d, _fretc(args(d)), names, folders


def test_testgen_writes_no_file_through_a_link(tmp_path):
    d, got, names, _folders = _writes_into(
        tmp_path, lambda out: ["testgen", R1, "-o", out, "--pytest"])
    assert got.returncode == 0, got.stderr
    assert {"T01.csv", "tests.json", "pytest.ini"} <= set(names)
    _check(tmp_path, d, got, names)


def test_testgen_with_bindings_writes_no_log_through_a_link(tmp_path):
    d, got, names, _folders = _writes_into(
        tmp_path, lambda out: ["testgen", R1, "-o", out, "-b",
                               ROOT / "requirements" / "safe_ros.bindings.toml"])
    assert got.returncode == 0, got.stderr
    assert any(n.endswith(".mcap") for n in names), names
    _check(tmp_path, d, got, names)


def test_testrun_refuses_a_linked_runs_folder_and_writes_no_json_through_a_link(tmp_path):
    tests = tmp_path / "tests"
    assert _fretc(["testgen", R1, "-o", tests]).returncode == 0
    _victim, victim_dir = _victims(tmp_path)
    (tests / "runs").symlink_to(victim_dir)
    (tests / "out.json").symlink_to(tmp_path / "victim.txt")
    got = _fretc(["testrun", tests, "--command", "cp", "--json", tests / "out.json"])
    assert got.returncode == 2 and "runs" in got.stderr and "link" in got.stderr, got.stderr
    _check(tmp_path, tests, got, [])
    (tests / "runs").unlink()
    got = _fretc(["testrun", tests, "--command", "cp", "--json", tests / "out.json"])
    assert got.returncode in (0, 1, 3), got.stderr
    _check(tmp_path, tests, got, ["out.json"])


def test_audit_write_csv_json_and_junit_write_no_file_through_a_link(tmp_path):
    logs = ROOT / "traces" / "nominal.mcap"
    d = _planted(tmp_path, ["nominal.csv", "a.json", "a.xml"], set())
    got = _fretc(["audit", "-r", R1, logs, "--write-csv", d, "--json", d / "a.json",
                  "--junit", d / "a.xml", "--no-progress"])
    assert got.returncode == 0, got.stderr
    _check(tmp_path, d, got, ["nominal.csv", "a.json", "a.xml"])


def test_report_writes_no_file_through_a_link_and_refuses_a_linked_timelines(tmp_path):
    doc = tmp_path / "audit.json"
    reqs = ROOT / "requirements"
    assert _fretc(["audit", "-r", reqs, ROOT / "traces" / "stop_delay.mcap", "--json", doc,
                   "--no-progress"]).returncode == 1
    d, got, names, folders = _writes_into(
        tmp_path, lambda out: ["report", "--requirements", reqs, "--from-json", doc, "-o", out])
    assert "timelines" in folders and "report.html" in names
    assert got.returncode == 2 and "timelines" in got.stderr, got.stderr
    (d / "timelines").unlink()
    got = _fretc(["report", "--requirements", reqs, "--from-json", doc, "-o", d])
    assert got.returncode == 1, got.stderr  # (a requirement violated on the run)
    _check(tmp_path, d, got, [n for n in names if n not in folders])


@pytest.mark.parametrize("form", ["c", "monitor", "psl"])
def test_emit_writes_no_file_through_a_link(form, tmp_path):
    d, got, names, _folders = _writes_into(
        tmp_path, lambda out: [ROOT / "requirements" / "safe_ros.fret", "--emit", form, "-o",
                               str(out) + "/"])
    assert got.returncode == 0, got.stderr
    _check(tmp_path, d, got, names)


def test_emit_to_a_file_named_by_a_link_replaces_the_link(tmp_path):
    victim, _ = _victims(tmp_path)
    out = tmp_path / "r1_monitors.py"
    out.symlink_to(victim)
    got = _fretc([R1, "--emit", "monitor", "-o", out])
    assert got.returncode == 0, got.stderr
    assert victim.read_text() == PRECIOUS and not out.is_symlink() and "MONITORS" in out.read_text()


def test_check_witnesses_and_json_write_no_file_through_a_link(tmp_path):
    fret = R1
    d, got, names, _folders = _writes_into(tmp_path, lambda out: ["check", fret, "--witness-dir",
                                                                  out])
    assert got.returncode in (0, 1), got.stderr
    _check(tmp_path, d, got, names)
    (d / "check.json").symlink_to(tmp_path / "victim.txt")
    got = _fretc(["check", fret, "-o", d / "check.json"])
    _check(tmp_path, d, got, ["check.json"])


def test_explain_writes_no_svg_through_a_link(tmp_path):
    d, got, names, _folders = _writes_into(tmp_path, lambda out: ["explain", R1, "-o", out])
    assert got.returncode == 0, got.stderr
    _check(tmp_path, d, got, names)


def test_watch_recorder_replaces_a_link(tmp_path):
    from fretc.live.record import Recorder

    victim, _ = _victims(tmp_path)
    out = tmp_path / "rec.mcap"
    out.symlink_to(victim)
    rec = Recorder(str(out), source=None)
    rec._f.close()
    assert victim.read_text() == PRECIOUS and not out.is_symlink()


SHIELD = ["shield", ROOT / "requirements" / "safe_ros.fret", "-b",
          ROOT / "requirements" / "safe_ros.bindings.toml", "--inputs",
          "too_close,scan_stale,clearance", "--outputs",
          "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed",
          "--emit", "python", "--emit", "c", "--emit", "ros2", "-o"]


def test_shield_writes_no_form_through_a_link_and_refuses_a_linked_package_folder(tmp_path):
    d, got, names, folders = _writes_into(tmp_path, lambda out: [*SHIELD, out])
    assert folders == {"safe_ros_shield_ros2"} and "safe_ros_shield.c" in names
    assert got.returncode == 2 and "safe_ros_shield_ros2" in got.stderr, got.stderr
    _check(tmp_path, d, got, [])
    (d / "safe_ros_shield_ros2").unlink()
    got = _fretc([*SHIELD, d])
    assert got.returncode == 0, got.stderr
    _check(tmp_path, d, got, [n for n in names if n not in folders])


def test_simulate_writes_no_svg_html_or_json_through_a_link(tmp_path):
    (tmp_path / "t.csv").write_text("too_close,stopped\n1,0\n0,1\n0,1\n", encoding="utf-8")
    d, got, names, _folders = _writes_into(
        tmp_path, lambda out: ["simulate", R1, tmp_path / "t.csv", "-o", out])
    assert got.returncode in (0, 1, 3), got.stderr
    assert "simulation.html" in names
    _check(tmp_path, d, got, names)
    (d / "s.json").symlink_to(tmp_path / "victim.txt")
    got = _fretc(["simulate", R1, tmp_path / "t.csv", "--json", d / "s.json"])
    _check(tmp_path, d, got, ["s.json"])


def test_distinguish_writes_no_svg_through_a_link(tmp_path):
    victim, _ = _victims(tmp_path)
    svg = tmp_path / "d.svg"
    svg.symlink_to(victim)
    got = _fretc(["distinguish", "the sw shall always satisfy p",
                  "the sw shall eventually satisfy p", "--svg", svg])
    assert got.returncode == 1, got.stdout + got.stderr
    assert victim.read_text() == PRECIOUS and not svg.is_symlink() and "<svg" in svg.read_text()


def test_export_and_annotate_write_nothing_through_a_link(tmp_path):
    doc = tmp_path / "audit.json"
    assert _fretc(["audit", "-r", R1, ROOT / "traces" / "nominal.mcap", "--json", doc,
                   "--no-progress"]).returncode == 0
    # (the annotated copy was written to NAME.part first, then renamed: a link there too)
    d = _planted(tmp_path, ["needs.json", "nominal.mcap", "nominal.mcap.part"], set())
    got = _fretc(["export", "--from-json", doc, "--needs", d / "needs.json"])
    assert got.returncode == 0, got.stderr
    got = _fretc(["report", "-r", R1, "--from-json", doc, "-o", tmp_path / "rep",
                  "--annotate", d])
    assert got.returncode == 0, got.stderr
    _check(tmp_path, d, got, ["needs.json", "nominal.mcap"])


def test_estimate_and_falsify_refuse_a_linked_runs_folder(tmp_path):
    """``fretc estimate``/``falsify`` keep their runs in OUT/runs (the runner makes it): a link
    planted there is refused, the folder it points to left as it was."""
    from fretc.sim.estimate import Runner

    _victim, victim_dir = _victims(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "runs").symlink_to(victim_dir)
    with pytest.raises(OSError, match="runs"):  # (fretc.common.outputs.OutputError)
        Runner(None, None, out)
    assert _state(victim_dir) == {"keep.txt": PRECIOUS}


@pytest.mark.tor("TOR-OUT-002")
def test_a_failed_write_is_an_output_error_naming_the_output(tmp_path):
    """An output whose temporary file cannot be made (no such folder), and a device written
    in place that fails the write (``/dev/full``: no space), are OutputErrors naming the
    output, never a bare OSError."""
    from fretc.common.outputs import OutputError, open_output

    missing = tmp_path / "no folder" / "out.json"  # (its temporary file cannot be made)
    with pytest.raises(OutputError, match="no folder"):
        with open_output(missing) as f:
            f.write("x")
    full = _device(tmp_path, "full", 7)
    with pytest.raises(OutputError, match=full):
        with open_output(full) as f:
            f.write("x" * 100_000)
            f.flush()


@pytest.mark.tor("TOR-OUT-001")
def test_an_output_inside_an_input_folder_is_refused_and_a_sibling_is_not(tmp_path):
    from fretc.common.outputs import OutputError, refuse_replacing_inputs

    runs = tmp_path / "runs"
    runs.mkdir()
    (tmp_path / "runs2").mkdir()
    with pytest.raises(OutputError, match="inside the log"):
        refuse_replacing_inputs([("--json", runs / "a.json")], [("the log", runs)])
    refuse_replacing_inputs([("--json", tmp_path / "runs2" / "a.json")], [("the log", runs)])
