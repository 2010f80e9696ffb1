"""``fretc watch`` ends with the run and agrees with ``fretc audit``: a log served by
``fretc replay --serve`` (foxglove-sdk) or by a local rosbridge-protocol server
(:mod:`rosbridge_server`, fed from the same log) is watched to the end without Ctrl-C, and the
watch's ``--json`` verdicts (verdict, first violation, ticks) and exit code equal those of
``fretc audit`` of the log; a rosbridge watch's ``--record`` audits the same. Ends of a run
(unadvertised topics, ``--until-idle``) are not data problems; a missing optional dependency
is one line and exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from click.testing import CliRunner  # noqa: E402

from fretc.cli import main  # noqa: E402
from rosbridge_server import RosbridgeTestServer  # noqa: E402

pytestmark = pytest.mark.watch

ROOT = Path(__file__).resolve().parents[2]
REQS = ["-r", str(ROOT / "requirements")]
REAL_REQS = ["-r", str(ROOT / "requirements" / "real_logs" / "cmd_vel_scaled.fret"),
             "-b", str(ROOT / "requirements" / "real_logs" / "cmd_vel_scaled.bindings.toml")]
#: topics the real log's requirements read, and the Safe-ROS requirements'
REAL_TOPICS = {"/scaled/cmd_vel", "/vehicle/cmd_vel"}
SAFE_ROS_TOPICS = {"/scan", "/cmd_vel_filtered", "/gwendolen_control", "/ground_truth/clearance"}
RATE = 50.0
ALL = sorted(p.stem for p in (ROOT / "traces").glob("*.mcap"))
#: every shipped trace, behind -m slow (the default run takes a fixed sample: conftest.py)
CASES = [pytest.param(name, marks=pytest.mark.slow, id=name) for name in ALL]


def _verdicts(doc: dict) -> list:
    """What must agree: per requirement the verdict, the first violation (tick, time,
    trigger), the LTL3 verdict, counts of ticks, triggers and violations; and the exit code."""
    out = []
    for v in doc["logs"][0]["verdicts"]:
        fv = v["first_violation"]
        out.append((v["requirement"], v["verdict"], v["error"] is None,
                    json.dumps(fv, sort_keys=True), v["ltl3"], v["ticks_evaluated"],
                    v["warmup_ticks"], v["triggers"], v["violations"]))
    return [out, doc["summary"]["exit_code"]]


def _audit(log: Path, reqs: list[str], tmp_path: Path) -> tuple[list, int]:
    out = tmp_path / "audit.json"
    res = CliRunner().invoke(main, ["audit", str(log), *reqs, "--json", str(out),
                                    "--no-progress"])
    assert res.exit_code in (0, 1, 3), res.output
    doc = json.loads(out.read_text())
    assert doc["summary"]["exit_code"] == res.exit_code
    return _verdicts(doc), res.exit_code


def _watch(url: str, reqs: list[str], tmp_path: Path, *extra: str):
    """``fretc watch URL --json`` to the end of the run (no --duration: the server ends it;
    a safety --duration of 90 s bounds a broken test)."""
    out = tmp_path / "watch.json"
    res = CliRunner().invoke(main, ["watch", url, *reqs, "--json", str(out), "--no-live",
                                    "--wait", "10", "--duration", "90", "--jsonl", *extra])
    assert out.exists(), res.output
    doc = json.loads(out.read_text())
    events = [json.loads(x) for x in res.output.splitlines() if x.startswith("{")]
    return _verdicts(doc), res.exit_code, doc, events


def _replay_serve(log: Path):
    """``fretc replay LOG --serve --port 0`` in a subprocess; (process, ws:// URL)."""
    proc = subprocess.Popen([sys.executable, "-m", "fretc", "replay", str(log), "--serve",
                             "--rate", str(RATE), "--port", "0"], cwd=str(ROOT),
                            stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()  # "serving LOG on ws://127.0.0.1:PORT at 50x"
    assert " on ws://" in line, line
    return proc, line.split(" on ", 1)[1].split(" ")[0]


def _via_replay(log: Path, reqs: list[str], tmp_path: Path):
    proc, url = _replay_serve(log)
    try:
        got = _watch(url, reqs, tmp_path)
        proc.wait(timeout=30)  # the server ended the run by itself
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stderr.close()
    return got


def _check_end(events: list, code: int, ref_code: int) -> None:
    ends = [e for e in events if e["event"] == "end"]
    assert len(ends) == 1 and ends[0]["detail"].startswith("the server closed the connection")
    assert code == ref_code


@pytest.mark.parametrize("name", CASES)
def test_replay_serve_watched_to_the_end_equals_audit(name, tmp_path):
    log = ROOT / "traces" / f"{name}.mcap"
    ref, ref_code = _audit(log, REQS, tmp_path)
    got, code, _doc, events = _via_replay(log, REQS, tmp_path)
    assert got == ref
    _check_end(events, code, ref_code)


@pytest.mark.parametrize("name", CASES)
def test_rosbridge_watched_to_the_end_equals_audit(name, tmp_path):
    log = ROOT / "traces" / f"{name}.mcap"
    ref, ref_code = _audit(log, REQS, tmp_path)
    rec = tmp_path / "watched.mcap"
    with RosbridgeTestServer(str(log), SAFE_ROS_TOPICS, rate=RATE) as srv:
        got, code, _doc, events = _watch(srv.url, REQS, tmp_path, "--record", str(rec))
    assert srv.sent > 0 and got == ref
    _check_end(events, code, ref_code)
    # the recording of the rosbridge watch (CDR from the JSON messages) audits the same
    again, again_code = _audit(rec, REQS, tmp_path)
    assert again == ref and again_code == ref_code


def test_real_log_served_both_ways_equals_audit(tmp_path, shared):
    log = shared / "data" / "logs" / "cmd_vel_scaled.mcap"
    ref, ref_code = _audit(log, REAL_REQS, tmp_path)
    got, code, _doc, events = _via_replay(log, REAL_REQS, tmp_path)
    assert got == ref
    _check_end(events, code, ref_code)
    with RosbridgeTestServer(str(log), REAL_TOPICS, rate=5.0) as srv:
        got, code, _doc, events = _watch(srv.url, REAL_REQS, tmp_path)
    assert got == ref
    _check_end(events, code, ref_code)


def test_rosbridge_without_rosapi_uses_the_given_types(tmp_path):
    """No rosapi: the topics' types come from the bindings' [types], /clock's from
    --topic-type."""
    log = ROOT / "traces" / "stop_delay.mcap"
    ref, ref_code = _audit(log, REQS, tmp_path)
    bindings = (ROOT / "requirements" / "safe_ros.bindings.toml").read_text(encoding="utf-8")
    with RosbridgeTestServer(str(log), SAFE_ROS_TOPICS, rate=RATE, rosapi=False) as srv:
        table = "".join(f'"{t}" = "{ty}"\n' for t, ty in sorted(srv.types.items()))
        typed = tmp_path / "typed.bindings.toml"
        typed.write_text(bindings + "\n[types]\n" + table, encoding="utf-8")
        reqs = [*REQS, "-b", str(typed)]
        got, code, _doc, events = _watch(srv.url, reqs, tmp_path,
                                         "--topic-type", "/clock=rosgraph_msgs/Clock")
    assert got == ref
    _check_end(events, code, ref_code)
