"""The per-entity variables evaluated over rows by numpy (audit/entities/rows.py) against the
reference, each variable evaluated at each tick for each entity (``entity_read.VECTORIZED``
off): on random small per-entity logs (numeric and text keys, keys repeated in a message,
NaN and infinite values, booleans), the values of every tick of every entity, the entities'
errors and the audit's verdicts are the same."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fretc.audit.entities.read as R
from _logs import ROS2, S, write_mcap
from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.audit.entities.rows import row_fields
from fretc.logs import open_log

OBJ, ARR = "entity_rows_msgs/msg/Obj", "entity_rows_msgs/msg/ObjArray"

VARIABLES = """dist = 'min(/objs.objs[:]{%(k)s==$obj}.distance)'
far = 'max(/objs.objs{%(k)s==$obj}.distance) - 1 >= 0.5'
ok = 'all(/objs.objs[:]{%(k)s==$obj}.ok)'
n = 'count(/objs.objs[:]{%(k)s==$obj}.ok) + len(/objs.objs[:]{%(k)s==$obj}.distance)'
m = 'abs(mean(/objs.objs[:]{%(k)s==$obj}.distance) * -2)'
any_ok = 'any(/objs.objs[:]{%(k)s==$obj}.ok) | dist < 0.5'
"""
FRET = ("@tick_period 100 ms\n"
        "R: the robot shall always satisfy (dist > 0.5 | !ok) & (n < 5 | far) & m > -1\n"
        "Q: upon any_ok the robot shall within 2 ticks satisfy !far\n")


def _types():
    from rosbags.typesys import get_types_from_msg

    if ARR not in ROS2.types:
        ROS2.register(get_types_from_msg("uint32 id\nstring label\nfloat64 distance\nbool ok",
                                         OBJ))
        ROS2.register(get_types_from_msg("entity_rows_msgs/Obj[] objs", ARR))
    return ROS2.types[OBJ], ROS2.types[ARR]


def _setup(tmp: Path, rows: list, key: str) -> tuple:
    Obj, Arr = _types()
    log = write_mcap(tmp / "o.mcap", [
        ("/objs", ARR, S + k * S // 10 + (k % 3) * S // 30,
         Arr(objs=[Obj(id=i, label=f"o{i}", distance=d, ok=ok) for i, d, ok in r]))
        for k, r in enumerate(rows)])
    (tmp / "o.fret").write_text(FRET)
    (tmp / "o.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\n[entities]\nobj = "/objs.objs[:].{key}"\n'
        "[variables]\n" + VARIABLES % {"k": key})
    return log, load_plan(AuditConfig(requirements=(str(tmp / "o.fret"),)))


def _read(log: Path, plan, vectorized: bool, monkeypatch) -> tuple:
    """Every tick's values (per-entity ones included) and the entities' errors."""
    names = ["dist", "far", "ok", "n", "m", "any_ok"]
    with monkeypatch.context() as mp:
        mp.setattr(R, "VECTORIZED", vectorized)
        made, ticks, errors = R.read_entities(open_log(str(log)), plan.bindings,
                                              {0: ("obj", names)}, 10**6)
    c = made[0]
    seen = [(t.time, repr(t.values[R.ENTITIES][0]), repr(_rows(t.values[R.ENTITIES][1], names)))
            for t in ticks[0] or c.lean_ticks()]
    return seen, c.table.keys, {i: str(e) for i, e in c.table.errors.items()}, \
        {k: str(e) for k, e in errors.items()}, c.evaluated


def _rows(rows, names: list[str]) -> list:
    """A tick's rows as (entity, ((value as float, whether a bool), ...)): the reference's
    list of (entity, values) or the vectorized path's rows of a batch."""
    if isinstance(rows, list):
        return [(i, tuple((float(v), type(v) is bool) for v in vals)) for i, vals in rows]
    blk = rows.block
    a, z = int(blk.offsets[rows.at]), int(blk.offsets[rows.at + 1])
    return [(int(blk.entity[k]), tuple((float(blk.values[n][0][k]), bool(blk.values[n][1][k]))
                                       for n in names)) for k in range(a, z)]


def _verdicts(la) -> list:
    whole = [v.verdict_of() if hasattr(v, "verdict_of") else v for v in la.verdicts]
    return [repr(dataclasses.replace(v, notes=[])) for v in whole]


ITEM = st.tuples(st.integers(1, 5),
                 st.sampled_from([0.2, 0.8, 1.7, 2.0, float("inf"), float("nan")]),
                 st.booleans())


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.lists(ITEM, max_size=4), min_size=1, max_size=15),
       key=st.sampled_from(["id", "label"]))
def test_rows_equal_the_reference(tmp_path_factory, monkeypatch, rows, key):
    """Vectorized rows == the tick-by-tick reference (values, errors, verdicts); a log
    whose messages never repeat a key is evaluated by the rows alone."""
    tmp = tmp_path_factory.mktemp("rows")
    log, plan = _setup(tmp, rows, key)
    fast = _read(log, plan, True, monkeypatch)
    slow = _read(log, plan, False, monkeypatch)
    assert fast[:4] == slow[:4], rows
    assert slow[4] == [0, 0]  # (the reference evaluates at each tick, not by rows)
    if all(len({i for i, _d, _o in r}) == len(r) for r in rows) and fast[1]:
        assert fast[4][1] == 0 and fast[4][0] > 0  # no repeated key: all by rows
    with monkeypatch.context() as mp:
        mp.setattr(R, "VECTORIZED", False)
        reference = audit_log(plan, str(log))
    assert _verdicts(audit_log(plan, str(log))) == _verdicts(reference)


def test_repeated_keys_fall_back_to_the_reference(tmp_path, monkeypatch):
    """Key 1 twice in a message: its rows have two items where the others have one; the
    batch is evaluated by the reference (min over both items: 0.2)."""
    log, plan = _setup(tmp_path, [[(1, 0.2, True), (1, 2.0, True), (2, 2.0, False)],
                                  [(2, 0.8, True)]], "id")
    seen, keys, errs, _e, evaluated = _read(log, plan, True, monkeypatch)
    assert evaluated[0] == 0 and evaluated[1] > 0
    assert keys == [1, 2] and not errs
    assert "(0, ((0.2, False)," in seen[0][2]


@pytest.mark.parametrize("expr, rows", [
    ("min(/objs.objs[:]{id==$obj}.distance)", True),
    ("min(/objs.objs[1:]{id==$obj}.distance)", False),  # a slice that is not every item
    ("min(/objs.objs[:]{id==2}.distance)", False),  # not the entity's filter
    ("age(/objs) + min(/objs.objs[:]{id==$obj}.distance)", False),
    ("min(/objs.objs[:]{id==$obj}.distance) + $obj", False),  # the key read as a value
])
def test_which_variables_the_rows_take(tmp_path, expr, rows):
    _types()
    log = write_mcap(tmp_path / "o.mcap", [("/objs", ARR, S, ROS2.types[ARR](objs=[]))])
    (tmp_path / "o.fret").write_text("@tick_period 100 ms\nR: the robot shall always satisfy "
                                     "v > 1\n")
    (tmp_path / "o.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\nobj = "/objs.objs[:].id"\n'
        f"[variables]\nv = '{expr}'\n")
    plan = load_plan(AuditConfig(requirements=(str(tmp_path / "o.fret"),)))
    from fretc.signals.bindings.expression import EntityParam

    own = plan.bindings.for_entity({"obj": EntityParam("obj")}).variables["v"]
    assert (row_fields([own], "/objs") is not None) == rows
    assert audit_log(plan, str(log)).verdicts  # audited either way


def test_write_csv_writes_the_per_entity_requirements_beside_the_plain_ones(tmp_path):
    """--write-csv of a set mixing a per-entity requirement with plain ones (the per-entity
    one was left out before, ``# fretc not sampled``): every requirement is written, each
    entity on a clock of its own, and the audit of the CSV gives every verdict of the log's,
    the entities' included."""
    import json

    from click.testing import CliRunner

    from fretc.cli import main
    from fretc.logs.csv.source import not_sampled_lines, per_entity_lines

    log, _plan = _setup(tmp_path, [[(1, 0.8, True), (2, 0.3, True)], [(1, 2.0, True)],
                                   [(2, 0.2, False)], [(1, 0.9, True)]], "id")
    (tmp_path / "o.fret").write_text(
        "@tick_period 100 ms\n"
        "E: the robot shall always satisfy dist > 0.5\n"
        "P: the robot shall always satisfy seen < 2\n"
        "Q: the robot shall always satisfy seen >= 1\n")
    (tmp_path / "o.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[entities]\nobj = "/objs.objs[:].id"\n[variables]\n'
        "dist = 'min(/objs.objs[:]{id==$obj}.distance)'\nseen = 'len(/objs.objs[:].id)'\n")
    reqs = ["-r", str(tmp_path / "o.fret")]
    res = CliRunner().invoke(main, ["audit", *reqs, str(log), "--write-csv",
                                    str(tmp_path / "csv"), "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 1, res.output  # E and P are violated on the log
    said = " ".join(res.output.split())
    assert "E 2 entities" in said and "not sampled" not in said, said
    csv = tmp_path / "csv" / "o.csv"
    assert not not_sampled_lines(csv)
    assert per_entity_lines(csv) == {"E": ("obj", ["E[obj=1]", "E[obj=2]"])}
    res = CliRunner().invoke(main, ["audit", *reqs, str(csv), "--json", str(tmp_path / "c.json")])
    assert res.exit_code == 1, res.output

    def seen(path):
        return [(v["requirement"], v["verdict"], v["ticks_evaluated"])
                for v in json.loads(path.read_text())["logs"][0]["verdicts"]]

    assert seen(tmp_path / "c.json") == seen(tmp_path / "a.json")
    assert ("E[obj=2]", "violated") in [x[:2] for x in seen(tmp_path / "c.json")]


DIAG_STATUS = st.dictionaries(st.sampled_from(["motor_l", "motor_r", "battery", "motor_3"]),
                              st.integers(0, 3), max_size=4)


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(DIAG_STATUS, st.integers(-40, 40)),
                     min_size=1, max_size=15),
       time=st.sampled_from(["log", "header"]))
def test_rows_equal_the_reference_on_diagnostics(tmp_path_factory, monkeypatch, rows, time):
    """Text keys with a ``matching`` glob, byte levels, the header time base (stamps off by
    up to 40 ms, some out of order): the rows' values and verdicts equal the reference's,
    every row evaluated by numpy."""
    from _logs import T, header

    tmp = tmp_path_factory.mktemp("diag")
    St, Arr = T(ROS2, "diagnostic_msgs/msg/DiagnosticStatus"), T(ROS2, "diagnostic_msgs/msg/DiagnosticArray")
    log = write_mcap(tmp / "d.mcap", [
        ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", S + k * S // 10,
         Arr(header=header(S + k * S // 10 + jitter * S // 1000),
             status=[St(level=lvl, name=n, message="", hardware_id="", values=[])
                     for n, lvl in sorted(statuses.items())]))
        for k, (statuses, jitter) in enumerate(rows)])
    (tmp / "d.fret").write_text("@tick_period 100 ms\n"
                                "M: in present mode the robot shall always satisfy lvl < 2\n")
    (tmp / "d.bindings.toml").write_text(
        f'[tick]\nperiod = "100 ms"\ntime = "{time}"\n[entities]\n'
        'motor = { key = "/diagnostics.status[:].name", matching = "motor*" }\n[variables]\n'
        "lvl = 'max(/diagnostics.status[:]{name==$motor}.level)'\n"
        "present = 'count(/diagnostics.status{name==$motor}.level >= 0) >= 1'\n")
    plan = load_plan(AuditConfig(requirements=(str(tmp / "d.fret"),)))
    got = []
    for vectorized in (True, False):
        with monkeypatch.context() as mp:
            mp.setattr(R, "VECTORIZED", vectorized)
            made, ticks, errors = R.read_entities(open_log(str(log)), plan.bindings,
                                                  {0: ("motor", ["lvl", "present"])}, 10**6)
            used = made[0].evaluated
            got.append(([(t.time, repr(t.values[R.ENTITIES][0]),
                          repr(_rows(t.values[R.ENTITIES][1], ["lvl", "present"])))
                         for t in ticks[0] or made[0].lean_ticks()], made[0].table.keys,
                        sorted(errors),
                        _verdicts(audit_log(plan, str(log)))))
        if vectorized and got[0][1]:
            assert used[0] > 0 and used[1] == 0  # (no name twice in a message: all by rows)
    assert got[0] == got[1], rows
