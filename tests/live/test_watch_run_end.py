"""How a watched run ends and what the command says: under ``--until-idle``, every subscribed
topic unadvertised (past the restart grace) and no message for the idle time end the run
without a data problem (exit 0 on a clean run, as ``fretc audit``; without ``--until-idle``
publishers leaving cut the run short: tests/live/test_watch_restart.py); data problems exit 3, 0 with ``--allow-partial``; the live table gives each
requirement its own clock's ticks and counts violated and pending obligations apart;
``watch --help`` lists only the watch's options; a missing optional dependency is one line
naming ``pip install 'fretc[watch]'`` and exit 2."""

from __future__ import annotations

import json
import re
import struct
import sys
import threading
import time

import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")

from click.testing import CliRunner  # noqa: E402

from fretc.cli import main  # noqa: E402
from fretc.audit import AuditConfig, load_plan  # noqa: E402
from fretc.monitors.interval import Evidence, Violation  # noqa: E402
from fretc.live.websocket.serve import FoxgloveServer  # noqa: E402
from fretc.live.watch import UNADVERTISED, Watch, WatchOptions, split_pending  # noqa: E402
from fretc.audit.verdict import exit_code  # noqa: E402
from test_watch import AB_BINDINGS  # noqa: E402

pytestmark = pytest.mark.watch

S = 1_000_000_000
T0 = 1_700_000_000 * S
FLOAT64 = ("std_msgs/msg/Float64", "ros2msg", b"float64 data")
BINDINGS = AB_BINDINGS
FRET = """@tick_period 100 ms
RA: the robot shall always satisfy a_ok
RB: the robot shall always satisfy b_ok
"""


def _f64(x: float) -> bytes:
    return b"\x00\x01\x00\x00" + struct.pack("<d", x)  # CDR little-endian header + value


@pytest.fixture()
def reqs(tmp_path):
    (tmp_path / "w.fret").write_text(FRET, encoding="utf-8")
    (tmp_path / "w.bindings.toml").write_text(BINDINGS, encoding="utf-8")
    return str(tmp_path / "w.fret")


def _serve(server, n=20, bad_at=None, then=None):
    """Publish ``n`` messages on /a and /b (50 ms apart; /b's payload truncated at
    ``bad_at``) once subscribed, then ``then(server)``; the server stays up."""
    def go():
        server.wait_subscribed({"/a", "/b"}, timeout=20)
        for k in range(n):
            server.log("/a", _f64(1.0), T0 + k * 50_000_000)
            server.log("/b", b"\x00\x01" if k == bad_at else _f64(1.0), T0 + k * 50_000_000)
            time.sleep(0.005)
        if then is not None:
            then(server)

    t = threading.Thread(target=go, daemon=True)
    t.start()
    return t


def _server():
    server = FoxgloveServer(port=0)
    server.channel("/a", "cdr", *FLOAT64)
    server.channel("/b", "cdr", *FLOAT64)
    return server


def test_every_topic_unadvertised_under_until_idle_ends_the_run_without_a_problem(reqs):
    plan = load_plan(AuditConfig(requirements=(reqs,)))
    server = _server()
    try:
        def unadvertise(srv):
            time.sleep(0.2)
            for ch in srv.channels.values():  # one unadvertise message per channel
                ch.close()

        w = Watch(plan, WatchOptions(url=server.url, wait=5.0, duration=30, until_idle=20.0,
                                     restart_grace=0.5))
        t = _serve(server, then=unadvertise)
        t0 = time.monotonic()
        la = w.run()
        took = time.monotonic() - t0
        t.join(10)
    finally:
        server.stop()
    assert w.source.end_reason.startswith("every publisher of the bound topics left")
    assert took < 25  # ended by the server, not by the 30 s bound
    assert not any(p["kind"] == UNADVERTISED for p in la.problems)
    assert [v.verdict for v in la.verdicts] == ["satisfied", "satisfied"]
    assert exit_code([la]) == 0


def _watch_cli(url, reqs, tmp_path, *extra):
    out = tmp_path / "w.json"
    res = CliRunner().invoke(main, ["watch", url, "-r", reqs, "--no-live", "--json", str(out),
                                    "--duration", "30", *extra])
    return res, json.loads(out.read_text())


def test_until_idle_ends_a_clean_run_with_exit_0(reqs, tmp_path):
    server = _server()
    try:
        t = _serve(server)
        res, doc = _watch_cli(server.url, reqs, tmp_path, "--until-idle", "500 ms", "--jsonl")
        t.join(10)
    finally:
        server.stop()
    assert res.exit_code == 0, res.output
    assert doc["summary"]["exit_code"] == 0 and doc["logs"][0]["problems"] == []
    ends = [json.loads(x) for x in res.output.splitlines() if x.startswith('{"')]
    ends = [e for e in ends if e["event"] == "end"]
    assert [e["detail"] for e in ends] == ["no message for 0.5 s"]
    # 0 .. 1 s: to the first tick at or after the last message (950 ms)
    assert [v["ticks_evaluated"] for v in doc["logs"][0]["verdicts"]] == [11, 11]


def test_data_problems_exit_3_and_0_with_allow_partial(reqs, tmp_path):
    codes = []
    for extra in ((), ("--allow-partial",)):
        server = _server()
        try:
            t = _serve(server, bad_at=5)
            res, doc = _watch_cli(server.url, reqs, tmp_path, "--until-idle", "0.5", *extra)
            t.join(10)
        finally:
            server.stop()
        # the lost message is a gap of the run: its value is not held over it
        assert [p["kind"] for p in doc["logs"][0]["problems"]] == ["undecodable",
                                                                    "undecodable_gap"]
        assert doc["summary"]["exit_code"] == res.exit_code
        codes.append(res.exit_code)
    assert codes == [3, 0]


def test_live_table_shows_each_clock_and_pending_apart(reqs):
    from rich.console import Console

    from fretc.cli.watch import live_table

    plan = load_plan(AuditConfig(requirements=(reqs,)))
    server = _server()
    try:
        w = Watch(plan, WatchOptions(url=server.url, wait=5.0, until_idle=0.5, duration=30))
        t = _serve(server)
        la = w.run()
        t.join(10)
    finally:
        server.stop()
    con = Console(record=True, width=200)
    con.print(live_table(w))
    text = con.export_text()
    head = text.splitlines()[0]
    assert not re.search(r"\| ticks \d", head)  # no sum over the requirements' clocks
    assert re.search(r"violated .* pending", text)
    for v in la.verdicts:
        row = next(x for x in text.splitlines() if f" {v.requirement} " in x)
        assert f"{v.ticks_evaluated} (1.0 s)" in row  # its own clock: 11 ticks, 0 .. 1 s


def test_pending_obligations_are_not_counted_as_violations():
    def fail(t, hi, at):
        return Violation(t, (0, 9), (t, hi), at, "")

    ev = Evidence(holds=False, vacuous=False, intervals=1, triggers=3, violations=3,
                  violation=None, ticks=10,
                  listed=[fail(2, 5, 5), fail(4, 4, 4), fail(8, 11, 9)])
    # triggers 2 and 4 failed inside the ticks seen; trigger 8's window reaches past tick 9
    assert split_pending(ev, 10) == (2, 1)
    assert split_pending(ev, 20) == (3, 0)


def test_watch_help_lists_only_its_own_options():
    runner = CliRunner()
    watch = runner.invoke(main, ["watch", "--help"]).output
    assert "--jobs" not in watch and "in parallel" not in watch
    for opt in ("--until-idle", "--allow-partial", "--duration", "--topic-type"):
        assert opt in watch
    assert "--jobs" in runner.invoke(main, ["audit", "--help"]).output


def test_missing_watch_extra_is_one_line_and_exit_2(monkeypatch, reqs):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "websockets" else real(name, *a))
    res = CliRunner().invoke(main, ["watch", "ws://127.0.0.1:9", "-r", reqs, "--no-live"])
    assert res.exit_code == 2
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "pip install 'fretc[watch]'" in lines[0], res.output
    monkeypatch.setitem(sys.modules, "foxglove", None)  # import foxglove fails
    res = CliRunner().invoke(main, ["replay", __file__, "--serve"])
    assert res.exit_code == 2
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "pip install 'fretc[watch]'" in lines[0], res.output


def test_bindings_types_table():
    from fretc.common.problems import BindingError
    from fretc.signals.bindings.files import parse_bindings

    b = parse_bindings(BINDINGS + '[types]\n"/a" = "std_msgs/msg/Float64"\n')
    assert b.types == {"/a": "std_msgs/msg/Float64"}
    assert b.with_inline(["c_ok=/a.data > 1"]).types == b.types
    with pytest.raises(BindingError, match=r"\[types\] needs"):
        parse_bindings(BINDINGS + '[types]\n"/a" = 3\n')


def test_a_server_stopped_from_two_threads_at_once_stops_without_an_error():
    """The run's end and the serving thread both stop the server (the qualification kit's
    watch check does): two concurrent stops of the library's server raise "Already
    borrowed", so :meth:`FoxgloveServer.stop` lets one thread take it and is idempotent."""
    errors: list[str] = []
    for _ in range(20):
        server = FoxgloveServer(port=0)
        both = threading.Barrier(2)

        def stop(server: FoxgloveServer = server, both: threading.Barrier = both) -> None:
            both.wait()
            try:
                server.stop()
            except Exception as e:  # noqa: BLE001 - the error is what the test reports
                errors.append(repr(e))

        threads = [threading.Thread(target=stop) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        server.stop()  # once more: nothing
    assert errors == []
