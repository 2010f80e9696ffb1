"""rosbag2's own service bags (``../shared/data/foreign_logs/rosbag2_services``, SOURCES.md):
``fretc inspect`` lists the service events of each (MCAP, a sqlite3 folder, a ``.db3``
given alone), and ``called``/``answered``/``waiting`` requirements on
``only_services.mcap`` give the verdicts of an independent decode by rosbags, its types
built from the ``.srv`` text the bag stores."""

from __future__ import annotations


import pytest
from click.testing import CliRunner

from _shared import SHARED, needs_shared
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli import main

BAGS = SHARED / "data" / "foreign_logs" / "rosbag2_services"
ALL = ["only_services.mcap", "topics_and_services.mcap",
       "bag_with_topics_and_service_events.mcap", "bag_with_topics_and_service_events",
       "topics_and_services_db3", "topics_and_services_db3/topics_and_services.db3"]
P = 100_000  # ns: the tick period, a tenth of a millisecond (the server answers in 0.2 ms)

INFO = """uint8 REQUEST_SENT = 0
uint8 REQUEST_RECEIVED = 1
uint8 RESPONSE_SENT = 2
uint8 RESPONSE_RECEIVED = 3
uint8 event_type
builtin_interfaces/Time stamp
char[16] client_gid
int64 sequence_number
"""


@needs_shared
@pytest.mark.parametrize("name", ALL)
def test_inspect_lists_the_service_events_of_every_bag(name):
    res = CliRunner().invoke(main, ["inspect", str(BAGS / name)])
    assert res.exit_code == 0, res.output
    assert "_service_event  " in res.output and "/_service_event.info.event_type" in res.output
    assert "not decoded" not in res.output


def _independent_events() -> list[tuple[int, int, bytes, int]]:
    """(log time, event type, client gid, sequence number) of every event of
    only_services.mcap, decoded by rosbags with the event type built from the stored
    ``.srv`` text (request above ``---``, response below)."""
    from mcap.reader import make_reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    out = []
    with open(BAGS / "only_services.mcap", "rb") as f:
        for schema, _ch, m in make_reader(f).iter_messages(log_time_order=True):
            if "t_AddTwoInts_Event" not in store.types:
                request, response = schema.data.decode().split("---")
                types = get_types_from_msg(INFO, "t/msg/ServiceEventInfo")
                types.update(get_types_from_msg(request, "t/msg/AddTwoInts_Request"))
                types.update(get_types_from_msg(response, "t/msg/AddTwoInts_Response"))
                types.update(get_types_from_msg(
                    "t/ServiceEventInfo info\nt/AddTwoInts_Request[<=1] request\n"
                    "t/AddTwoInts_Response[<=1] response\n", "t/msg/AddTwoInts_Event"))
                store.register(types)
            e = store.deserialize_cdr(m.data, "t/msg/AddTwoInts_Event")
            out.append((m.log_time, int(e.info.event_type), bytes(e.info.client_gid),
                        int(e.info.sequence_number)))
    return out


def _waits(events, ticks: list[int]) -> list[float]:
    """``waiting()`` at each tick: seconds the oldest call open at it has waited."""
    opened: dict[tuple, int] = {}
    spans = []
    for t, kind, gid, seq in events:
        if kind <= 1:
            opened.setdefault((gid, seq), t)
        elif (gid, seq) in opened:
            spans.append((opened.pop((gid, seq)), t))
    return [max([t - a for a, b in spans if a <= t < b], default=0) / 1e9 for t in ticks]


@pytest.mark.tor("TOR-LOG-001")
@needs_shared
def test_service_requirements_on_rosbag2s_own_bag_match_an_independent_decode(tmp_path):
    (tmp_path / "s.fret").write_text(
        "W1: the server shall always satisfy wait <= 0.001\n"
        "W2: the server shall always satisfy wait <= 0.0001\n"
        "C: upon req the server shall within 3 ticks satisfy resp\n"
        "C1: upon req the server shall within 1 tick satisfy resp\n")
    (tmp_path / "s.bindings.toml").write_text(
        f'[tick]\nperiod = "{P // 1000} us"\n[variables]\nwait = "waiting(/add_two_ints)"\n'
        'req = "called(/add_two_ints)"\nresp = "answered(/add_two_ints)"\n')
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "s.fret"),)))
    la = audit_log(plan, str(BAGS / "only_services.mcap"))
    got = {v.requirement: v for v in la.verdicts}
    events = _independent_events()
    assert [k for _t, k, _g, _s in events] == [1, 2] * 6  # server side: received, sent
    first = got["W1"].first_tick_ns
    ticks = list(range(first, events[-1][0] + P, P))
    waits = _waits(events, ticks)
    assert got["W1"].verdict == ("satisfied" if max(waits) <= 0.001 else "violated")
    over = next(k for k, w in enumerate(waits) if w > 0.0001)
    assert got["W2"].verdict == "violated"
    assert got["W2"].first_violation.at.time_ns == ticks[over]
    # a request is answered within 3 ticks (0.3 ms), never within 1 (0.1 ms)
    req = [t for t, k, _g, _s in events if k <= 1]
    resp = [t for t, k, _g, _s in events if k >= 2]
    slots = [(-(-(a - first) // P), -(-(b - first) // P)) for a, b in zip(req, resp)]
    assert got["C"].verdict == ("satisfied" if all(b - a <= 3 for a, b in slots) else "violated")
    assert got["C1"].verdict == ("satisfied" if all(b - a <= 1 for a, b in slots) else "violated")
    assert {v.verdict for v in got.values()} == {"satisfied", "violated"}


@pytest.mark.tor("TOR-LOG-001")
@needs_shared
def test_a_storage_file_alone_reads_as_its_folder_with_metadata(tmp_path):
    """The .db3 given alone (as rosbag2 opens one): the same messages as the bag folder
    with its metadata.yaml (the same storage, copied next to a made metadata.yaml)."""
    from fretc.logs import open_log

    alone = open_log(BAGS / "topics_and_services_db3" / "topics_and_services.db3")
    folder = open_log(BAGS / "topics_and_services_db3")
    msgs = [(m.topic, m.log_time) for m in alone.messages()]
    assert msgs and msgs == [(m.topic, m.log_time) for m in folder.messages()]
    assert alone.topics()["/add_two_ints/_service_event"] == \
        "example_interfaces/srv/AddTwoInts_Event"
    sums = [m.data.response[0].sum for m in alone.messages({"/add_two_ints/_service_event"})
            if len(m.data.response)]
    assert sums and all(isinstance(s, int) for s in sums)


@needs_shared
@pytest.mark.parametrize("inline", [False, True])
def test_count_ticks_of_called(tmp_path, inline):
    """``count_ticks(called(/svc), 1 s)``, bound to a variable of its own or written inline:
    the ticks in the last second at which a request came (the server is called every 0.5 s:
    two), equal to a count from the independent decode."""
    (tmp_path / "c.fret").write_text("@tick_period 100 ms\nN1: the server shall always "
                                     "satisfy n <= 1\nN2: the server shall always satisfy "
                                     "n <= 2\n")
    inner = "called(/add_two_ints)" if inline else "c"
    (tmp_path / "c.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\n[variables]\nc = "called(/add_two_ints)"\n'
        f'n = "count_ticks({inner}, 1 s)"\n')
    la = audit_log(load_plan(AuditConfig(requirements=(str(tmp_path / "c.fret"),))),
                   str(BAGS / "only_services.mcap"))
    got = {v.requirement: v for v in la.verdicts}
    req = [t for t, k, _g, _s in _independent_events() if k <= 1]
    tick = 100_000_000
    first = got["N2"].first_tick_ns  # the first tick whose window is full (1 s in)
    ticks = [-(-t // tick) * tick for t in req]  # the tick that folds each request
    counts = {t: sum(1 for x in ticks if t - 1_000_000_000 < x <= t)
              for t in range(first, ticks[-1] + tick, tick)}
    assert got["N2"].verdict == ("satisfied" if max(counts.values()) <= 2 else "violated")
    bad = min(t for t, c in counts.items() if c > 1)
    assert got["N1"].verdict == "violated" and got["N1"].first_violation.at.time_ns == bad


def test_a_fold_inside_an_expression_is_named_as_written(tmp_path):
    """``called(/arm) & ok``: the error names called(/arm), not the any_of_messages() it
    stands for."""
    from fretc.common.problems import BindingError
    from fretc.signals.bindings.binding import compile_expression

    with pytest.raises(BindingError) as e:
        compile_expression("x", "called(/arm) & /ok.data", source="b.toml")
    assert "called(/arm) is the whole binding" in str(e.value)
    assert "any_of_messages" not in str(e.value).split("(e.g.")[0]
