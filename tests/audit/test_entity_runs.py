"""A lean per-entity clock's ticks recorded as runs (audit/entities/runs.py) against the
tick-by-tick clock (``entity_read.LEAN`` off): on random logs whose messages are several
ticks apart or within one tick, the ticks (times, log times, per-entity values), the
sampling's figures and the audit's JSON are the same, whether the messages are recorded
one at a time (``entity_runs.LEAN_BATCH`` 0) or by batches that end anywhere."""

from __future__ import annotations

import json

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import fretc.audit.entities.log as E
import fretc.audit.entities.read as R
import fretc.audit.entities.runs as RU
from _logs import S, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.logs import open_log
from test_entity_rows import ARR, FRET, VARIABLES, _rows, _types

NAMES = ["dist", "far", "ok", "n", "m", "any_ok"]
ITEM = st.tuples(st.integers(1, 5), st.sampled_from([0.2, 0.8, 1.7, float("nan")]),
                 st.booleans())


def _setup(tmp, rows):
    Obj, Arr = _types()
    t, msgs = S, []
    for gap, items in rows:
        t += gap * S // 100  # (gaps of 0 to 450 ms: none, one or several ticks between)
        msgs.append(("/objs", ARR, t, Arr(objs=[Obj(id=i, label=f"o{i}", distance=d, ok=ok)
                                                for i, d, ok in items])))
    log = write_mcap(tmp / "o.mcap", msgs)
    (tmp / "o.fret").write_text(FRET)
    (tmp / "o.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\nobj = "/objs.objs[:].id"\n[variables]\n'
        + VARIABLES % {"k": "id"})
    return log, load_plan(AuditConfig(requirements=(str(tmp / "o.fret"),)))


def _read(log, plan, lean, monkeypatch, batch=RU.LEAN_BATCH, bound=10**6):
    with monkeypatch.context() as mp:
        mp.setattr(R, "LEAN", lean)
        mp.setattr(RU, "LEAN_BATCH", batch)
        made, ticks, errors = R.read_entities(open_log(str(log)), plan.bindings,
                                              {0: ("obj", NAMES)}, bound)
        la = audit_log(plan, str(log))
    c = made[0]
    assert c.lean == lean and (not lean or not ticks[0])
    s = c.s
    seen = [(t.index, t.time, t.log_times, repr(t.values[R.ENTITIES][0]),
             repr(_rows(t.values[R.ENTITIES][1], NAMES)))
            for t in (c.lean_ticks() if lean else ticks[0])]
    figures = (s.ticks, s.warmup_ticks, s.start_time, s.end_time, s.first_time,
               dict(s.unsampled), s.missing_topics, c.index, c.next_grid)
    return (seen, figures, c.table.keys, c.table.first, c.table.last, c.table.cut, sorted(errors),
            json.dumps(la.to_json(), sort_keys=True))


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(st.integers(0, 45), st.lists(ITEM, max_size=3)),
                     min_size=1, max_size=12),
       batch=st.sampled_from([0, 1, 3, RU.LEAN_BATCH]), bound=st.sampled_from([2, 4, 10**6]))
def test_runs_equal_the_ticks(tmp_path_factory, monkeypatch, rows, batch, bound):
    log, plan = _setup(tmp_path_factory.mktemp("runs"), rows)
    lean = _read(log, plan, True, monkeypatch, batch, bound)
    ticks = _read(log, plan, False, monkeypatch, batch, bound)
    assert lean == ticks, rows


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(st.integers(0, 45), st.lists(ITEM, max_size=3)),
                     min_size=1, max_size=12))
@example(rows=[(10, [(1, 0.2, True), (2, 0.3, True), (3, 0.4, True)])] * 3)  # (alike lives)
def test_violated_entities_robustness_at_once_equals_one_at_a_time(tmp_path_factory,
                                                                   monkeypatch, rows):
    """The robustness of the entities the batch finds violated, computed at once over their
    traces end to end (``entities.BATCH_ROBUSTNESS``), gives the audit JSON of each computed
    over its own trace: values, ticks, margins and evidence."""
    log, plan = _setup(tmp_path_factory.mktemp("rob"), rows)
    with monkeypatch.context() as mp:
        mp.setattr(E, "BATCH_ROBUSTNESS", False)
        one = json.dumps(audit_log(plan, str(log)).to_json(), sort_keys=True)
    assert json.dumps(audit_log(plan, str(log)).to_json(), sort_keys=True) == one, rows
