"""Outputs that would replace inputs are refused (hostile round 9, R1 and N4):
``fretc shield-replay SH d/a.mcap d/a.shielded.mcap -o d`` overwrote its second input before
reading it and reported on it (exit 0); ``--json PATH`` could name an input; ``fretc audit
runs/*.csv --write-csv runs`` replaced each input CSV with its sampled trace. Now every
such command exits 2 before writing anything, naming the output and the input, whether the
two paths are equal, a symbolic link to the other, or a hard link."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.common.outputs import OutputError, refuse_replacing_inputs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "shield"))
from _replay import REPO, TRACE, docs_shield  # noqa: E402

CSV = "time,x\n0,1\n1,2\n"
FRET = "R: the robot shall always satisfy x > 0\n"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _snapshot(folder: Path) -> dict:
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


@pytest.fixture
def runs(tmp_path):
    (tmp_path / "runs").mkdir()
    for n in ("a", "b"):
        (tmp_path / "runs" / f"{n}.csv").write_text(CSV)
    (tmp_path / "r.fret").write_text(FRET)
    return tmp_path


def test_audit_write_csv_into_the_folder_of_its_input_csvs_is_refused(runs):
    """N4's smallest input: before, exit 0 and runs/a.csv replaced by its sampled trace."""
    before = _snapshot(runs)
    got = _run("audit", runs / "runs" / "a.csv", runs / "runs" / "b.csv", "-r", runs / "r.fret",
               "--write-csv", runs / "runs")
    assert got.exit_code == 2, got.output
    assert "--write-csv" in got.output and "a.csv" in got.output and "the log" in got.output
    assert _snapshot(runs) == before


@pytest.mark.parametrize("option,target", [("--json", "r.fret"), ("--junit", "runs/a.csv"),
                                           ("--json", "runs/b.csv")])
@pytest.mark.tor("TOR-OUT-001")
def test_audit_json_or_junit_naming_an_input_is_refused(runs, option, target):
    before = _snapshot(runs)
    got = _run("audit", runs / "runs" / "a.csv", runs / "runs" / "b.csv", "-r", runs / "r.fret",
               option, runs / target)
    assert got.exit_code == 2, got.output
    assert option in got.output and Path(target).name in got.output
    assert _snapshot(runs) == before


@pytest.mark.parametrize("how", ["symlink", "hardlink", "dotdot"])
@pytest.mark.tor("TOR-OUT-001")
def test_an_input_reached_another_way_is_the_same_input(runs, how):
    """Resolved, links followed; a hard link by its inode."""
    a = runs / "runs" / "a.csv"
    other = runs / "other.csv"
    if how == "symlink":
        other.symlink_to(a)
    elif how == "hardlink":
        os.link(a, other)
    else:
        other = runs / "runs" / ".." / "runs" / "a.csv"
    before = _snapshot(runs)
    got = _run("audit", other, "-r", runs / "r.fret", "--json", a)
    assert got.exit_code == 2, got.output
    assert _snapshot(runs) == before


def test_outputs_apart_from_the_inputs_are_written(runs):
    got = _run("audit", runs / "runs" / "a.csv", "-r", runs / "r.fret", "--json",
               runs / "out.json", "--write-csv", runs / "csv")
    assert got.exit_code == 0, got.output
    assert (runs / "out.json").exists() and (runs / "csv" / "a.csv").exists()
    assert (runs / "runs" / "a.csv").read_text() == CSV


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(names=st.lists(st.sampled_from(["a", "b", "c", "d"]), min_size=1, max_size=4),
       out=st.sampled_from(["a", "b", "c", "d", "e"]), link=st.booleans())
def test_the_helper_refuses_exactly_the_outputs_that_are_inputs(tmp_path, names, out, link):
    """The check's definition: refused iff the output resolves to one of the inputs."""
    folder = tmp_path / "f"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    for n in "abcd":
        (folder / n).write_text(n)
    if link:
        (folder / "e").symlink_to(folder / "a")
    inputs = [("the log", folder / n) for n in names]
    target = "a" if out == "e" and link else out
    want = target in names
    try:
        refuse_replacing_inputs([("--json", folder / out), ("--json", None), ("--json", "-")],
                                inputs)
    except OutputError as exc:
        assert want, exc
        assert "--json" in str(exc) and "the log" in str(exc)
    else:
        assert not want


def test_an_output_inside_a_rosbag2_folder_given_as_a_log_is_refused(tmp_path):
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("x")
    with pytest.raises(OutputError, match="inside the log"):
        refuse_replacing_inputs([("--json", bag / "metadata.yaml")], [("the log", bag)])
    refuse_replacing_inputs([("--json", tmp_path / "bag.json")], [("the log", bag)])


@pytest.fixture(scope="module")
def shield_dir(tmp_path_factory) -> Path:
    return docs_shield(tmp_path_factory.mktemp("shield"))


@pytest.mark.tor("TOR-OUT-001")
def test_shield_replay_output_that_is_its_second_input_is_refused(shield_dir, tmp_path):
    """R1's input: d/a.mcap and d/a.shielded.mcap given, -o d. Before, the second was
    overwritten with the first's replay before it was read, and reported on (exit 0)."""
    d = tmp_path / "d"
    d.mkdir()
    shutil.copy(TRACE, d / "a.mcap")
    shutil.copy(TRACE, d / "a.shielded.mcap")
    before = _snapshot(d)
    reqs = ["-r", REPO / "requirements" / "safe_ros.fret", "-r",
            REPO / "requirements" / "shield" / "release.fret"]
    got = _run("shield-replay", shield_dir, d / "a.mcap", d / "a.shielded.mcap", "-o", d, *reqs)
    assert got.exit_code == 2, got.output
    assert "-o" in got.output and "a.shielded.mcap" in got.output
    assert "Traceback" not in got.output
    assert _snapshot(d) == before
    got = _run("shield-replay", shield_dir, d / "a.mcap", "-o", tmp_path / "out", *reqs,
               "--json", d / "a.mcap")
    assert got.exit_code == 2, got.output
    assert "--json" in got.output
    assert _snapshot(d) == before and not (tmp_path / "out").exists()


def test_report_and_export_outputs_naming_their_inputs_are_refused(runs):
    """fretc report -o DIR where DIR/audit.json is its --from-json; fretc export --needs
    naming its --from-json, --matrix naming its requirements (-r)."""
    (runs / "out").mkdir()
    got = _run("audit", runs / "runs" / "a.csv", "-r", runs / "r.fret", "--json",
               runs / "out" / "audit.json")
    assert got.exit_code == 0, got.output
    before = _snapshot(runs)
    got = _run("report", "--from-json", runs / "out" / "audit.json", "-o", runs / "out")
    assert got.exit_code == 2, got.output
    assert "--from-json" in got.output and "audit.json" in got.output
    got = _run("report", runs / "runs" / "a.csv", "-r", runs / "r.fret", "-o", runs / "runs" / "..")
    assert got.exit_code == 0, got.output  # (writes report.html ..., none of them an input)
    before = _snapshot(runs)
    for extra in (["--needs", runs / "out" / "audit.json"],
                  ["-r", runs / "r.fret", "--matrix", runs / "r.fret"]):
        got = _run("export", "--from-json", runs / "out" / "audit.json", *extra)
        assert got.exit_code == 2, got.output
        assert "an output never replaces an input" in got.output
    assert _snapshot(runs) == before
