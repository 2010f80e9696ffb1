"""The audit's reaction allowance (``fretc audit --allowance TOPIC=DURATION``, ``[audit]
allowance`` of a binding file; :mod:`fretc.logs.allowance`): the messages of a topic read as
if logged that much earlier, so that an answer seen on the bus within the allowance after
its tick is judged at that tick; no allowance (or 0) reads exactly what the audit read
without one; the allowance is stated wherever a verdict is; a bad one is a usage error."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.log import audit_keeping_passes
from fretc.cli import main
from fretc.common.problems import BindingError
from fretc.logs.allowance import AllowanceSource, parse_allowance, with_allowance
from fretc.logs.base import Gap, LogSource, Message
from fretc.signals.bindings import parse_bindings

from _logs import MS, boolean, write_mcap

ROOT = Path(__file__).resolve().parents[2]
BOOL = "std_msgs/msg/Bool"

#: the trigger on /req, the answer on /ans: ``immediately`` asks for it at the same tick
FRET = "A1: whenever asked shield shall immediately satisfy answered\n"
BINDINGS = """[tick]
period = "100 ms"

[variables]
asked = "/req.data"
answered = "/ans.data"
"""


def _answered_late(path: Path, late_ms: int = 50) -> Path:
    """A run whose /req turns true at 1 s and false at 2 s and whose /ans follows each
    change ``late_ms`` later (the node's latency on the bus)."""
    msgs = []
    for k in range(31):
        t = k * 100 * MS
        msgs.append(("/req", BOOL, t, boolean(1000 <= k * 100 < 2000)))
        msgs.append(("/ans", BOOL, t + late_ms * MS, boolean(1000 <= k * 100 < 2000)))
    msgs.sort(key=lambda m: m[2])
    return write_mcap(path, msgs)


def _files(tmp_path: Path, bindings: str = BINDINGS) -> Path:
    (tmp_path / "a.fret").write_text(FRET)
    (tmp_path / "a.bindings.toml").write_text(bindings)
    return tmp_path / "a.fret"


def _audit(*args: object) -> object:
    res = CliRunner().invoke(main, ["audit", "--no-progress", *map(str, args)])
    if res.exception and not isinstance(res.exception, SystemExit):
        raise res.exception
    return res


def test_an_answer_within_the_allowance_is_judged_at_its_tick(tmp_path):
    fret = _files(tmp_path)
    log = _answered_late(tmp_path / "run.mcap")
    without = _audit("-r", fret, log, "--json", tmp_path / "n.json")
    assert without.exit_code == 1, without.output  # seen one tick late: violated
    res = _audit("-r", fret, log, "--allowance", "/ans=100ms", "--json", tmp_path / "a.json")
    assert res.exit_code == 0, res.output
    assert "allowance: /ans read 100 ms earlier" in res.output
    doc = json.loads((tmp_path / "a.json").read_text())
    assert doc["bindings"]["allowance_ns"] == {"/ans": 100 * MS}
    assert doc["logs"][0]["allowance_ns"] == {"/ans": 100 * MS}
    assert doc["logs"][0]["messages"] == json.loads(
        (tmp_path / "n.json").read_text())["logs"][0]["messages"]  # (none lost)
    # an allowance shorter than the answer's lateness does not hide it
    short = _audit("-r", fret, log, "--allowance", "/ans=40ms")
    assert short.exit_code == 1, short.output


def test_the_violation_evidence_states_the_allowance(tmp_path):
    fret = _files(tmp_path)
    log = _answered_late(tmp_path / "run.mcap", late_ms=250)
    res = _audit("-r", fret, log, "--allowance", "/ans=100ms", "--json", tmp_path / "a.json")
    assert res.exit_code == 1, res.output
    assert "read with the allowance: /ans read 100 ms earlier" in res.output
    v = json.loads((tmp_path / "a.json").read_text())["logs"][0]["verdicts"][0]
    assert v["first_violation"]["allowance_ns"] == {"/ans": 100 * MS}


def test_no_allowance_and_a_zero_one_write_the_same_bytes(tmp_path):
    fret = _files(tmp_path)
    log = _answered_late(tmp_path / "run.mcap")
    outs = []
    for extra in ([], ["--allowance", "/ans=0ms"]):
        out = tmp_path / f"{len(extra)}.json"
        res = _audit("-r", fret, log, *extra, "--json", out)
        outs.append((res.exit_code, res.output, out.read_bytes()))
    assert outs[0] == outs[1]


@pytest.mark.parametrize("value, said", [
    ("/nope=10ms", "no binding reads the topic /nope"),
    ("/ans=-5ms", "cannot be negative"),
    ("/ans=soon", "is not a duration"),
    ("/ans", "is not TOPIC=DURATION"),
    ("/ans=10Hz", "not a frequency"),
])
def test_a_bad_allowance_is_a_usage_error_naming_the_option(tmp_path, value, said):
    fret = _files(tmp_path)
    log = _answered_late(tmp_path / "run.mcap")
    res = CliRunner().invoke(main, ["audit", "--no-progress", "-r", str(fret), str(log),
                                    "--allowance", value])
    assert res.exit_code == 2, res.output
    assert "--allowance" in res.output and said in res.output


def test_the_binding_files_allowance_reads_as_the_option(tmp_path):
    fret = _files(tmp_path, BINDINGS + '\n[audit]\nallowance = {"/ans" = "100 ms"}\n')
    log = _answered_late(tmp_path / "run.mcap")
    res = _audit("-r", fret, log, "--json", tmp_path / "f.json")
    assert res.exit_code == 0, res.output
    assert "allowance: /ans read 100 ms earlier" in res.output
    # the option, topic by topic, over the file's
    over = _audit("-r", fret, log, "--allowance", "/ans=0ms")
    assert over.exit_code == 1, over.output
    assert "allowance" not in over.output.splitlines()[0]


@pytest.mark.parametrize("table, said", [
    ('[audit]\nallowance = {"/nope" = "1 ms"}\n', "no binding of this file reads /nope"),
    ('[audit]\nallowance = {"/ans" = "-1 ms"}\n', "cannot be negative"),
    ('[audit]\nallowance = "1 ms"\n', "a table of topics to durations"),
    ('[audit]\nslack = {"/ans" = "1 ms"}\n', "unknown key 'slack' in [audit]"),
])
def test_a_bad_audit_table_names_its_line(table, said):
    with pytest.raises(BindingError) as exc:
        parse_bindings(BINDINGS + "\n" + table, "b.toml")
    assert said in str(exc.value) and "b.toml:" in str(exc.value)


def test_parse_allowance():
    assert parse_allowance("120ms") == 120 * MS
    assert parse_allowance(" 0 ms") == 0 and parse_allowance("0") == 0
    for bad in ("-1 ms", "1 Hz", "x"):
        with pytest.raises(ValueError):
            parse_allowance(bad)


def test_streamed_whole_and_parallel_audits_agree(tmp_path):
    fret = _files(tmp_path)
    log = _answered_late(tmp_path / "run.mcap", late_ms=250)
    plan = load_plan(AuditConfig(requirements=(str(fret),), allowance=(("/ans", 100 * MS),)))
    streamed = audit_log(plan, str(log))
    whole = audit_keeping_passes(plan, str(log)).audit
    assert [v.to_json(0) for v in streamed.verdicts] == [v.to_json(0) for v in whole.verdicts]
    assert streamed.verdicts[0].verdict == "violated"
    other = _answered_late(tmp_path / "run2.mcap", late_ms=50)
    one, two = tmp_path / "1.json", tmp_path / "2.json"
    _audit("-r", fret, log, other, "--allowance", "/ans=100ms", "--json", one)
    _audit("-r", fret, log, other, "--allowance", "/ans=100ms", "--json", two, "-j", "2")
    assert one.read_bytes() == two.read_bytes()
    assert [la["verdicts"][0]["verdict"] for la in json.loads(one.read_text())["logs"]] == [
        "violated", "satisfied"]


class _Listed(LogSource):
    """A source of listed messages and gaps (log time order)."""

    kind = "mcap"

    def __init__(self, msgs: list[Message], gaps: list[Gap]) -> None:
        super().__init__("listed")
        self.msgs, self.listed_gaps = msgs, gaps

    def topics(self) -> dict[str, str]:
        return {"/a": BOOL, "/b": BOOL}

    def messages(self, topics=None):
        self._begin_pass()
        for g in self.listed_gaps:
            self._gap(g.start, g.end, topics=g.topics, cause=g.cause)
        for m in self.msgs:
            if topics is None or m.topic in topics:
                yield m


def _m(topic: str, t: int) -> Message:
    return Message(topic, t, t, t, None)


def test_the_shifted_topic_keeps_every_message_in_order():
    msgs = sorted([_m("/a", t) for t in range(0, 1000, 7)]
                  + [_m("/b", t) for t in range(3, 1000, 5)], key=lambda m: m.log_time)
    src = with_allowance(_Listed(msgs, []), {"/b": 40})
    assert isinstance(src, AllowanceSource)
    got = list(src.messages())
    times = [m.log_time for m in got]
    assert times == sorted(times)
    assert sorted((m.topic, m.log_time + (40 if m.topic == "/b" else 0)) for m in got) == \
        sorted((m.topic, m.log_time) for m in msgs)
    assert all(m.header_stamp == m.log_time for m in got)  # (the stamp shifted with it)
    # a tie keeps the log's order: the /a message logged first
    tie = list(with_allowance(_Listed([_m("/a", 10), _m("/b", 50)], []), {"/b": 40}).messages())
    assert [(m.topic, m.log_time) for m in tie] == [("/a", 10), ("/b", 10)]


def test_gaps_of_the_shifted_topic_shift_with_it():
    gaps = [Gap(100, 200, frozenset({"/b"}), "chunk_crc"),
            Gap(300, 400, frozenset({"/a"}), "chunk_crc"),
            Gap(500, 600, None, "chunk_crc"), Gap(700, None, None, "truncated")]
    src = with_allowance(_Listed([_m("/a", 0)], gaps), {"/b": 40})
    list(src.messages())
    assert src.gaps == [Gap(60, 160, frozenset({"/b"}), "chunk_crc"),
                        Gap(300, 400, frozenset({"/a"}), "chunk_crc"),
                        Gap(460, 600, None, "chunk_crc"), Gap(660, None, None, "truncated")]
    assert src.cut_start == 660 and src.damage_time == 60


def test_no_allowance_is_the_source_itself():
    src = _Listed([], [])
    assert with_allowance(src, None) is src and with_allowance(src, {"/b": 0}) is src
