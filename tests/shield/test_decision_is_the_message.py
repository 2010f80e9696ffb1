"""A shield's decision is the message it sends (KP-124): the outputs its machines step on and
report are the bindings of one message, in every form.

Two shields whose outputs share one message. The TurtleBot3 user's of the finding:

    TB1: upon obstacle_near the turtlebot shall within 1 second satisfy ! driving_forward
    TB2: the turtlebot shall always satisfy cmd_linear <= 0.22

with ``driving_forward = /cmd_vel_out.linear.x > 0.01`` and ``cmd_linear =
/cmd_vel_out.linear.x`` (a boolean and a number of one field): stepped with ``linear.x =
+inf`` (``driving_forward`` true) the shield replaced the number with 0.0 and kept
``driving_forward``, a command no message gives, and its machine believed the robot driving
that the command stopped. And Safe-ROS's Safety System on a TurtleBot3 (``stopped``,
``forwarded_zero``, ``linear_speed = abs(linear.x)``, ``angular_speed``, ``linear_velocity
= linear.x``: several outputs of one field, ``abs`` among them, and ``lateral =
linear.y``, an output no requirement reads, passed through).

Random runs (hypothesis) of random proposals, each a Twist whose fields are numbers, NaN,
±inf or huge (read through the bindings, ``[tick] inf = "value"``: +inf is
``driving_forward``), and random inputs (a range, NaN among them), through the Python form,
the C form (gcc, sanitizers), the ROS 2 node's decision (:class:`fretc.shield.messages.
MessageShield` with the generated shield and rosbags messages, as the node runs it, without a
graph) and ``fretc shield-replay`` (over an MCAP of the run): at every tick

* the outputs reported are the bindings evaluated on the message published (the node and the
  replay: the message they publish; the Python and C forms, which publish none: the message
  written from the outputs, which must give them all back);
* each machine stepped on those messages: its next belief is the one the atoms of the
  published values lead to from its belief before the tick;
* and FRET's interval semantics finds no enforced requirement violated on the run of the
  published messages (with the inputs' true values where the shield read NaN).
"""

from __future__ import annotations

import csv
import io
import math
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.monitors.interval import verdict_of
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import load_shield, render_python
from fretc.shield.messages import MessageShield, default_message
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.files import load_bindings

from _c_monitors import build as build_c, needs_cc, write

PERIOD = 100_000_000  # ns
TYPES = {"/range": "std_msgs/msg/Float64", "/cmd_vel": "geometry_msgs/msg/Twist",
         "/cmd_vel_out": "geometry_msgs/msg/Twist", "/stop_request": "std_msgs/msg/Bool"}
HEAD = "[tick]\nperiod = \"100 ms\"\ninf = \"value\"\n\n[variables]\n"
SHIELD = ("\n[shield]\nproposals = { \"/cmd_vel_out\" = \"/cmd_vel\" }\n"
          "originates = [\"/stop_request\"]\ntypes = { \"/stop_request\" = "
          "\"std_msgs/msg/Bool\", \"/cmd_vel_out\" = \"geometry_msgs/msg/Twist\" }\n")

CONFIGS = {
    "tb3_finding": {
        "fret": "@tick_period 100 ms\n"
                "TB1: upon obstacle_near the turtlebot shall within 1 second satisfy "
                "! driving_forward\n"
                "TB2: the turtlebot shall always satisfy cmd_linear <= 0.22\n",
        "bindings": HEAD + 'obstacle_near = "/range.data < 0.3"\n'
                           'driving_forward = "/cmd_vel_out.linear.x > 0.01"\n'
                           'cmd_linear = "/cmd_vel_out.linear.x"\n'
                    + SHIELD.replace('originates = ["/stop_request"]\n', "")
                            .replace('"/stop_request" = "std_msgs/msg/Bool", ', ""),
        "inputs": ["obstacle_near"], "outputs": ["driving_forward", "cmd_linear"],
        "ticks": {"TB1": 10}},
    "safe_ros_tb3": {
        "fret": "@tick_period 100 ms\n"
                "R2: upon too_close turtlebot shall within 1 second satisfy stopped\n"
                "R3: whenever stop_requested turtlebot shall immediately satisfy "
                "forwarded_zero\n"
                "R4: the turtlebot shall always satisfy linear_speed <= 0.22 & "
                "angular_speed <= 0.3\n"
                "R9: whenever obstacle_ahead turtlebot shall immediately satisfy "
                "linear_velocity <= 0\n",
        "bindings": HEAD + 'too_close = "/range.data < 0.25"\n'
                           'obstacle_ahead = "/range.data < 0.5"\n'
                           'stopped = "abs(/cmd_vel_out.linear.x) < 1e-3 & '
                           'abs(/cmd_vel_out.angular.z) < 1e-3"\n'
                           'stop_requested = "/stop_request.data"\n'
                           'forwarded_zero = "/cmd_vel_out.linear.x = 0 & '
                           '/cmd_vel_out.linear.y = 0 & /cmd_vel_out.linear.z = 0 & '
                           '/cmd_vel_out.angular.x = 0 & /cmd_vel_out.angular.y = 0 & '
                           '/cmd_vel_out.angular.z = 0"\n'
                           'linear_speed = "abs(/cmd_vel_out.linear.x)"\n'
                           'angular_speed = "abs(/cmd_vel_out.angular.z)"\n'
                           'linear_velocity = "/cmd_vel_out.linear.x"\n'
                           'lateral = "/cmd_vel_out.linear.y"\n' + SHIELD,
        "inputs": ["too_close", "obstacle_ahead"],
        "outputs": ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                    "angular_speed", "linear_velocity", "lateral"],
        "ticks": {"R2": 10}},
}

#: a Twist field's proposed value: numbers near the thresholds, NaN, ±inf, huge
FIELD = st.one_of(st.sampled_from([0.0, -0.0, 1e-4, 0.005, 0.0105, 0.02, 0.1, 0.22, 0.3, 0.5,
                                   -0.2, -0.5, 1e300, -1e300, math.inf, -math.inf,
                                   math.nan]),
                  st.floats(-1.0, 1.0))
#: a range (m): obstacles near and far, no return (+inf), NaN (the shield cannot read it)
RANGE = st.sampled_from([0.2, 0.4, 1.0, math.inf, math.nan])


@st.composite
def ticks(draw, most: int = 30, c_host: bool = False
          ) -> list[dict[str, Any]]:
    """A run: per tick the proposed Twist's fields, the proposed stop request, the range
    and, for a NaN range, the range it truly was (``c_host``: no NaN range, which a C
    boolean input cannot carry, and no NaN in ``linear.y``, read by ``lateral``, which the C
    form does not read: a C host reads ``forwarded_zero`` false there, no message's value)."""
    out = []
    for _ in range(draw(st.integers(1, most))):
        out.append({"lx": draw(FIELD), "az": draw(FIELD),
                    "ly": draw(st.sampled_from([0.0, 0.0, 0.3] + [math.nan] * (not c_host))),
                    "ax": draw(st.sampled_from([0.0, 0.0, 0.1])),
                    "stop": draw(st.booleans()),
                    "range": draw(RANGE if not c_host else RANGE.filter(lambda r: r == r)),
                    "truly": draw(st.sampled_from([0.2, 0.4, 1.0]))})
    return out


class Setup:
    """A configuration's shield (Python class, C folder), bindings and type store."""

    def __init__(self, name: str, folder: Path):
        from rosbags.typesys import Stores, get_typestore

        cfg = CONFIGS[name]
        self.name, self.cfg, self.folder = name, cfg, folder
        (folder / f"{name}.fret").write_text(cfg["fret"], encoding="utf-8")
        self.bindings_file = folder / f"{name}.bindings.toml"
        self.bindings_file.write_text(cfg["bindings"], encoding="utf-8")
        self.bindings = load_bindings(self.bindings_file)
        self.compiled = compile_entries(load_requirements([folder / f"{name}.fret"]))
        self.shield = build_shield(self.compiled, cfg["inputs"], cfg["outputs"],
                                   bindings=self.bindings, fork=False, name=name)
        self.text = render_python(self.shield)
        self.cls = load_shield(self.text)
        self.store = get_typestore(Stores.ROS2_JAZZY)
        self.enforced = {r.id for r in self.shield.requirements}

    def message(self, topic: str, **fields: Any) -> Any:
        """A message of ``topic``'s type, its default with ``fields`` (``linear__x``)."""
        msg = default_message(self.store, TYPES[topic])
        for key, value in fields.items():
            owner = msg
            path = key.split("__")
            for name in path[:-1]:
                owner = getattr(owner, name)
            setattr(owner, path[-1], value)
        return msg

    def read(self, msgs: dict[str, Any], names: list[str]) -> dict[str, Any]:
        """The variables ``names`` through the bindings on ``msgs`` (topic -> message); a
        binding that cannot be evaluated gives NaN."""
        s = EvalState()
        s.msgs, s.now, s.times = dict(msgs), 0, {t: 0 for t in msgs}
        out: dict[str, Any] = {}
        for v in names:
            try:
                out[v] = self.bindings.variables[v].evaluate(s)
            except Exception:  # noqa: BLE001 - (a value the host cannot read)
                out[v] = math.nan
        return out

    def proposal_messages(self, tick: dict[str, Any]) -> dict[str, Any]:
        """The tick's proposal as the corrected topics' messages."""
        cmd = self.message("/cmd_vel", linear__x=tick["lx"], linear__y=tick["ly"],
                           angular__x=tick["ax"], angular__z=tick["az"])
        return {"/cmd_vel_out": cmd, "/stop_request": self.message("/stop_request",
                                                                   data=tick["stop"])}

    def written(self, outputs: dict[str, Any]) -> dict[str, Any]:
        """The message a host writes from outputs of the Python or C form: each field from
        the output bound to it (``linear.x`` from the signed velocity, else ``cmd_linear``
        or the speed; ``angular.z`` from the speed; ``linear.y`` from ``lateral``, 0
        without it), ``angular.x`` (no output but ``forwarded_zero`` reads it) zero unless
        ``forwarded_zero`` is false while no other field is a number other than zero (then
        1): a complete writer, so outputs some message gives come back."""
        o = outputs
        lx = o.get("linear_velocity", o.get("cmd_linear", o.get("linear_speed", 0.0)))
        az = o.get("angular_speed", 0.0)
        ly = o.get("lateral", 0.0)
        moving = lx != 0 or az != 0 or (ly == ly and ly != 0)  # (a NaN compares unknown)
        ax = 1.0 if o.get("forwarded_zero") is False and not moving else 0.0
        return {"/cmd_vel_out": self.message("/cmd_vel_out", linear__x=float(lx),
                                             linear__y=float(ly), angular__x=ax,
                                             angular__z=float(az)),
                "/stop_request": self.message("/stop_request",
                                              data=bool(o.get("stop_requested", False)))}


@pytest.fixture(scope="module", params=sorted(CONFIGS))
def setup(request, tmp_path_factory):
    return Setup(request.param, tmp_path_factory.mktemp(request.param))


def same(a: Any, b: Any) -> bool:
    """Equal values: booleans as booleans, numbers exactly (NaN equal to NaN)."""
    if isinstance(a, bool) or isinstance(b, bool):
        return isinstance(a, (bool, np.bool_)) and isinstance(b, (bool, np.bool_)) \
            and bool(a) == bool(b)
    a, b = float(a), float(b)
    return a == b or (a != a and b != b)


def assert_is_message(setup: Setup, reported: dict[str, Any], msgs: dict[str, Any],
                      where: str) -> dict[str, Any]:
    """The outputs ``reported`` are the bindings of ``msgs``; the values read back."""
    back = setup.read(msgs, [v for v in setup.cfg["outputs"] if v in reported])
    wrong = {v: (reported[v], back[v]) for v in back if not same(reported[v], back[v])}
    assert not wrong, f"{where}: decided != the message's bindings: {wrong}"
    return back


def _states(held: tuple) -> list[tuple[int, ...]] | None:
    """The states of one machine's entry of :attr:`ShieldRuntime.state` (None: lost)."""
    if held and held[0] == "lost":
        return None
    return [tuple(x) for x in held[1:]] if held and held[0] == "belief" else [tuple(held)]


def assert_stepped_on(rt: Any, before: tuple, after: tuple, inputs: dict[str, Any],
                      values: dict[str, Any], where: str) -> None:
    """Each machine of ``rt`` moved from ``before`` to ``after`` (:attr:`state` before and
    after the tick) as the atoms of ``values`` (the published outputs) lead it, with every
    case of an unread input."""
    ins, unread = rt._readable(inputs)
    for m, held, now in zip(rt.machines, before, after, strict=True):
        states, got = _states(held), _states(now)
        if states is None or got is None:
            continue  # (the fallback's outputs until reset)
        outs = tuple(int(f(values)) for f in m.out_tests)
        cases = [(st, i) for i in m.input_cases(ins, frozenset(unread)) for st in states]
        assert all(m.move(i, outs, st)[0] for st, i in cases), \
            f"{where}: the published outputs are not safe for {m.reqs}"
        want = sorted({m.move(i, outs, st)[1] for st, i in cases})
        assert sorted(got) == want, f"{where}: {m.reqs} stepped on other atoms than published"


def assert_requirements_hold(setup: Setup, rows: list[dict[str, Any]], where: str) -> None:
    """FRET's verdict of each enforced requirement on the published run is not violated."""
    if not rows:
        return
    cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    for c in setup.compiled:
        if c.id in setup.enforced:
            verdict = verdict_of(c.entry.requirement, cols, len(rows),
                                 setup.cfg["ticks"].get(c.id))
            assert verdict != "violated", f"{where}: {c.id} violated on the published run"


def inputs_of(setup: Setup, tick: dict[str, Any], truly: bool = False) -> dict[str, Any]:
    """The inputs through the bindings on the tick's range (``truly``: NaN replaced by the
    range it truly was)."""
    r = tick["range"] if not (truly and tick["range"] != tick["range"]) else tick["truly"]
    return setup.read({"/range": setup.message("/range", data=r)}, setup.cfg["inputs"])


def proposal_of(setup: Setup, tick: dict[str, Any], c_host: bool = False) -> dict[str, Any]:
    """The tick's proposal through the bindings; ``c_host``: as a C host reads it, a
    boolean whose comparisons read NaN false (IEEE: every comparison these bindings make
    with NaN is false; a C ``bool`` holds no NaN)."""
    proposal = setup.read(setup.proposal_messages(tick), setup.cfg["outputs"])
    if c_host:
        proposal = {v: (False if v in setup.shield.read and v not in setup.shield.numbers
                            and x != x else x) for v, x in proposal.items()}
    return proposal


def python_run(setup: Setup, run: list[dict[str, Any]], c_host: bool = False
               ) -> list[tuple[dict, dict, Any]]:
    """The Python form over ``run``, checked at every tick; (inputs, proposal, decision)
    (``c_host``: the proposals as a C host reads them, :func:`proposal_of`)."""
    rt = setup.cls()
    rows, out = [], []
    for k, tick in enumerate(run):
        inputs = inputs_of(setup, tick)
        proposal = proposal_of(setup, tick, c_host)
        before = rt.state
        d = rt.step(inputs, proposal)
        out.append((inputs, proposal, d))
        if not d.outputs:
            continue  # (no fallback: nothing to publish)
        where = f"python tick {k} {tick}: {d}"
        back = assert_is_message(setup, d.outputs, setup.written(d.outputs), where)
        assert_stepped_on(rt, before, rt.state, inputs, back, where)
        rows.append({**inputs_of(setup, tick, truly=True), **back})
    assert_requirements_hold(setup, rows, "python")
    return out


SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.function_scoped_fixture])


@SETTINGS
@given(run=ticks())
@pytest.mark.tor("TOR-SHD-001")
def test_the_python_forms_decision_is_one_message(setup, run):
    python_run(setup, run)


def test_the_findings_infinite_proposal_is_the_fallbacks_stop(tmp_path):
    """The finding's tick: ``linear.x = +inf`` is a message the shield cannot read, so
    every output it carries is replaced by the fallback's (the stop), ``driving_forward``
    included; before, ``driving_forward`` stayed true beside ``cmd_linear = 0.0``."""
    setup = Setup("tb3_finding", tmp_path)
    rt = setup.cls()
    proposal = setup.read(setup.proposal_messages(
        {"lx": math.inf, "ly": 0.0, "ax": 0.0, "az": 0.0, "stop": False}),
        setup.cfg["outputs"])
    assert proposal == {"driving_forward": True, "cmd_linear": math.inf}
    d = rt.step({"obstacle_near": False}, proposal)
    assert d.outputs == {"driving_forward": False, "cmd_linear": 0.0}, d
    assert d.overridden and "cmd_linear is inf" in d.fault, d
    assert set(d.changed) == {"driving_forward", "(cmd_linear <= 0.22)"}, d


def test_a_speed_limited_beside_its_signed_velocity_is_one_field(tmp_path):
    """``linear_speed = abs(linear.x)`` limited to 0.22 (R4) beside ``linear_velocity =
    linear.x``, whose atom the limit leaves true: the velocity is the limited field's,
    -0.22, not the proposal's -0.754 (no Twist gives both)."""
    setup = Setup("safe_ros_tb3", tmp_path)
    rt = setup.cls()
    tick = {"lx": -0.754, "ly": 0.0, "ax": 0.0, "az": 0.0, "stop": False}
    d = rt.step({"too_close": False, "obstacle_ahead": False}, proposal_of(setup, tick))
    assert d.outputs["linear_speed"] == 0.22 and d.outputs["linear_velocity"] == -0.22, d
    assert d.reasons == ("R4",), d


def test_a_declared_fallback_no_message_gives_is_refused(tmp_path):
    """``--fallback '!driving_forward, cmd_linear=0.1'``: its atoms keep TB1 and TB2, but
    ``linear.x = 0.1`` drives forward: no message gives both, and the shield says so."""
    from fretc.shield.plan import ShieldError

    setup = Setup("tb3_finding", tmp_path)
    with pytest.raises(ShieldError, match="no one message the bindings give: cmd_linear=0.1"):
        build_shield(setup.compiled, setup.cfg["inputs"], setup.cfg["outputs"],
                     bindings=setup.bindings, fork=False,
                     fallback={"driving_forward": False, "cmd_linear": 0.1})


@SETTINGS
@given(run=ticks())
@pytest.mark.tor("TOR-SHD-005")
def test_the_ros2_nodes_decision_is_the_message_it_publishes(setup, run):
    shield = MessageShield(setup.cls(), setup.bindings, {"/cmd_vel_out": "/cmd_vel"},
                           lambda topic: default_message(setup.store, TYPES[topic]))
    rows = []
    for k, tick in enumerate(run):
        t = (k + 1) * PERIOD
        shield.hear("/range", setup.message("/range", data=tick["range"]), t)
        shield.hear("/cmd_vel", setup.proposal_messages(tick)["/cmd_vel_out"], t)
        before = shield.runtime.state
        try:
            d, msgs = shield.tick(t)
        except Exception as exc:  # noqa: BLE001 - (no fallback: nothing published)
            assert "nothing to publish" in str(exc), exc
            continue
        where = f"ros2 tick {k} {tick}: {d}"
        back = assert_is_message(setup, d.outputs, dict(shield.published), where)
        assert_stepped_on(shield.runtime, before, shield.runtime.state, shield._inputs(t),
                          back, where)
        rows.append({**inputs_of(setup, tick, truly=True), **back})
    assert_requirements_hold(setup, rows, "ros2")


def run_c(setup: Setup, run: list[dict[str, Any]]) -> list[dict[str, str]]:
    """The C runner of the setup's shield (sanitizers on) over ``run``: per tick a row."""
    folder = setup.folder / "c"
    if not (folder / "run").exists():
        write(render_c(setup.shield, "t"), folder)
        build_c(folder, ["t_shield.c", "t_shield_run.c"], "run")
    ins = [v for v in setup.shield.inputs if v in setup.shield.read]
    outs = [v for v in setup.shield.outputs if v in setup.shield.read]
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(ins + outs)
    for tick in run:
        inputs = inputs_of(setup, tick)
        proposal = proposal_of(setup, tick, c_host=True)
        w.writerow([_cell(inputs[v]) for v in ins] + [_cell(proposal[v]) for v in outs])
    got = subprocess.run([str(folder / "run")], input=text.getvalue(), capture_output=True,
                         text=True, timeout=60)
    assert got.returncode == 0 and not got.stderr, got.stderr
    return list(csv.DictReader(io.StringIO(got.stdout)))


def _cell(x: Any) -> str:
    return ("true" if x else "false") if isinstance(x, (bool, np.bool_)) else repr(float(x))


@SETTINGS
@given(run=ticks(c_host=True))
@pytest.mark.tor("TOR-SHD-004")
def test_the_c_forms_decision_is_one_message_and_the_pythons(setup, run):
    needs_cc()
    rows = run_c(setup, run)
    decided = python_run(setup, run, c_host=True)
    published = []
    for k, (tick, row, (_i, _p, d)) in enumerate(zip(run, rows, decided, strict=True)):
        outs = {v: (row[v] == "1") if not setup.shield.numbers.__contains__(v)
                else float(row[v]) for v in setup.cfg["outputs"] if v in row}
        where = f"c tick {k} {tick}: {row}"
        for v, x in outs.items():
            assert same(x, d.outputs[v]), f"{where}: C {v}={x}, Python {d.outputs[v]}"
        back = assert_is_message(setup, outs, setup.written(outs), where)
        published.append({**inputs_of(setup, tick, truly=True), **back})
    assert_requirements_hold(setup, published, "c")


class _Recording(MessageShield):
    """The replay's MessageShield, each tick's state before, inputs, decision and the
    messages held after it kept."""

    log: list[tuple[Any, ...]] = []

    def tick(self, now_ns):  # noqa: D102 - MessageShield.tick, recorded
        before = self.runtime.state
        d, msgs = super().tick(now_ns)
        _Recording.log.append((before, self.runtime.state, self._inputs(now_ns), d,
                               dict(self.published), self.runtime))
        return d, msgs


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                 HealthCheck.function_scoped_fixture])
@given(run=ticks(most=20))
@pytest.mark.tor("TOR-SHD-007")
def test_shield_replays_records_are_the_messages_it_writes(setup, run, monkeypatch,
                                                           tmp_path_factory):
    from fretc.shield import replay
    from fretc.shield.replay import load_folder, replay_log

    from _logs import write_mcap

    folder = tmp_path_factory.mktemp("replay")
    shield_dir = folder / "shield"
    shield_dir.mkdir()
    (shield_dir / f"{setup.name}_shield.py").write_text(setup.text, encoding="utf-8")
    (shield_dir / f"{setup.name}.bindings.toml").write_text(setup.cfg["bindings"],
                                                             encoding="utf-8")
    messages = []
    for k, tick in enumerate(run):
        t = k * PERIOD + 1_000_000
        messages.append(("/range", TYPES["/range"], t,
                         setup.message("/range", data=tick["range"])))
        messages.append(("/cmd_vel", TYPES["/cmd_vel"], t,
                         setup.proposal_messages(tick)["/cmd_vel_out"]))
    log = write_mcap(folder / "run.mcap", messages)
    _Recording.log = []
    monkeypatch.setattr(replay, "MessageShield", _Recording)
    result = replay_log(load_folder(shield_dir), log, folder / "shielded.mcap")
    assert _Recording.log and result.ticks >= len(_Recording.log)
    for k, (before, after, inputs, d, held, rt) in enumerate(_Recording.log):
        where = f"replay tick {k}: {d}"
        back = assert_is_message(setup, d.outputs, held, where)
        assert_stepped_on(rt, before, after, inputs, back, where)
