"""The validation suite's checks of the shield's forms that run beside a robot's ROS 2 graph
and under AJPF: the ROS 2 node (``--emit ros2``) built with ROS 2 Jazzy's rclpy and driven
message by message (:mod:`fretc.qualification.ros2_node`), the Gwendolen agent's Java
machine (``--emit gwendolen``) stepped by the JDK, and AJPF run on the agent by ``fretc
ajpf``; each held against the shield's Python form (which the ``shield-python`` check holds
against the reference evaluator) and the reference evaluator itself.

Each needs what a machine may lack (rclpy; a JDK; a built MCAPL and a Java 11 runtime) and
raises :class:`CheckSkipped` naming it.
"""

from __future__ import annotations

import json
import math
import os
import random
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from fretc.qualification import reference as ref
from fretc.qualification.checks import SEED, Check, CheckSkipped, Run, _bits, _capped
from fretc.qualification.checks_audit import fretc
from fretc.qualification.checks_forms import SHIELD_KEYS, _folder, _load, shield_command
from fretc.qualification.ros2_node import GRAPH_WAIT

#: the ROS 2 types of the shield's topics and its proposal (the node ticks on /x)
SHIELD_ROS2 = ('\n[shield]\nproposals = { "/o" = "/o_proposed" }\ntick = "/x"\n'
               'types = { "/x" = "std_msgs/msg/Float64", "/o" = "std_msgs/msg/Bool", '
               '"/o_proposed" = "std_msgs/msg/Bool" }\n')
#: random runs the ROS 2 node is driven over
NODE_RUNS = 16
#: the node's tick (the bindings' 100 ms) and when a proposal comes before its tick, in ns
PERIOD_NS = 100_000_000
PROPOSAL_LEAD_NS = 40_000_000
#: seconds the node's process (rclpy's start included) may take
NODE_TIMEOUT = 180


def _ros2_forms(run: Run) -> tuple[Path, Any] | list[str]:
    """The check shield's ``--emit ros2`` package folder and Python form's ``Shield``, or
    the failure of ``fretc shield``."""
    folder = _folder(run, "shield-ros2")
    args = shield_command(folder)
    with open(folder / "s.toml", "a", encoding="utf-8") as f:
        f.write(SHIELD_ROS2)
    code, text = fretc(run, [*args, "--emit", "ros2", "--emit", "python",
                             "-o", str(folder / "out")])
    if code != 0 or not (folder / "out" / "s_shield_ros2").is_dir():
        return [f"fretc shield --emit ros2 exited {code}: {text.strip()[-300:]}"]
    return folder / "out", _load(folder / "out" / "s_shield.py").Shield


def _node_runs() -> list[list[tuple[str, str, Any, int]]]:
    """Seeded random runs of the node's messages: per tick a proposal 40 ms before it
    (sometimes bytes that are no Bool, never twice running so the last one read is not yet
    absent), then /x, which ticks the node (a number, NaN, an infinity, or bytes that are no
    Float64)."""
    rnd = random.Random(SEED + 11)
    runs = []
    for _ in range(NODE_RUNS):
        events: list[tuple[str, str, Any, int]] = []
        bad_before = True  # (the first tick's proposal is read: none is held before it)
        for k in range(rnd.randint(3, 10)):
            t = 10**9 + k * PERIOD_NS
            bad = not bad_before and rnd.random() < 0.12
            events.append(("garbage" if bad else "message", "/o_proposed",
                           rnd.random() < 0.35, t - PROPOSAL_LEAD_NS))
            bad_before = bad
            draw = rnd.random()
            x: Any = (math.nan if draw < 0.12 else rnd.choice([math.inf, -math.inf])
                      if draw < 0.18 else float(rnd.randint(0, 9)))
            events.append(("garbage" if rnd.random() < 0.08 else "message", "/x", x, t))
        runs.append(events)
    return runs


#: the graph run's steps, ``[x, proposed o]`` each held until the node answered: S1 forcing
#: o, the proposal kept, NaN (the fallback), the proposal kept again
GRAPH_STEPS: list[list[Any]] = [[9.0, False], [2.0, False], [math.nan, False], [2.0, True]]


def _drive(run: Run, package: Path, runs: list[Any], graph: bool = False) -> list[Any]:
    """:func:`fretc.qualification.ros2_node.drive` (``graph``: its ``on_graph``) in a
    process of its own (a ROS domain of its own, discovery kept on this host), its output
    parsed. Raises RuntimeError when the process fails."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(100 + os.getpid() % 100),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONDONTWRITEBYTECODE": "1",
           # (rclpy's log files in the work folder, and Fast DDS without its shared-memory
           # files in /dev/shm: nothing written outside the report's folder)
           "ROS_HOME": str(run.work / "ros"), "ROS_LOG_DIR": str(run.work / "ros" / "log"),
           "FASTDDS_BUILTIN_TRANSPORTS": "UDPv4"}
    got = subprocess.run([sys.executable, "-m", "fretc.qualification.ros2_node",
                          str(package / "s_shield_ros2"), "s_shield_ros2",
                          *(["--graph"] if graph else [])],
                         input=json.dumps(runs), capture_output=True, text=True,
                         timeout=NODE_TIMEOUT, env=env, cwd=run.work)
    if got.returncode != 0:
        raise RuntimeError(f"the node's process exited {got.returncode}: "
                           f"{got.stderr.strip()[-600:]}")
    return list(json.loads(got.stdout.splitlines()[-1]))


def check_shield_ros2(run: Run) -> list[str]:
    """The check shield's ROS 2 node, built with rclpy, driven over seeded random runs
    (:func:`_node_runs`): a proposal read between ticks is answered at once with the Python
    form's decision from the last tick's state; after each tick the last message on /o (what
    the base obeys) is the Python form's output; an unreadable value or bytes that are no
    message give an ERROR on /diagnostics (the fallback's message sent at a fault tick), a
    readable tick none; no message ends the node; the commands on the bus keep S1 and S2 by
    the reference evaluator, unread values read both ways. Then the node on a ROS 2 graph
    (its own publishers and timer, a probe node publishing :data:`GRAPH_STEPS`): what
    reaches the probe is the Python form's decision and fault (:func:`_judge_graph`)."""
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        raise CheckSkipped("ROS 2 Jazzy's rclpy is not importable (the ros-jazzy-rclpy "
                           f"wheels, or a sourced ROS 2 Jazzy): {exc}") from None
    forms = _ros2_forms(run)
    if isinstance(forms, list):
        return forms
    package, shield_class = forms
    runs = _node_runs()
    got = _drive(run, package, runs)
    out: list[str] = []
    seen = {"a proposal corrected between ticks": 0, "a tick overridden": 0,
            "a fault tick": 0, "bytes that are no message": 0}
    for n, (events, answers) in enumerate(zip(runs, got, strict=True)):
        out += _judge_run(n, events, answers, shield_class(), seen)
    out += [f"the runs have no {what}: they do not show the node's answer to it"
            for what, count in seen.items() if not count]
    return _capped(out + _judge_graph(_drive(run, package, GRAPH_STEPS, graph=True),
                                      shield_class()))


def _judge_graph(got: list[dict[str, Any]], shield: Any) -> list[str]:
    """The graph run (:data:`GRAPH_STEPS`) against the Python form stepped five ticks on
    each step's values: the node's last three ``/o`` messages are its last output, an ERROR
    on ``/diagnostics`` exactly where it has a fault, at least a WARN where it overrides."""
    out = []
    for (x, proposed), heard in zip(GRAPH_STEPS, got, strict=True):
        for _ in range(5):
            d = shield.step({"x": x}, {"o": proposed})
        want = bool(d.outputs["o"])
        where = f"on the graph, x = {x}, o proposed {proposed}"
        if len(heard["o"]) < 3 or len(heard["levels"]) < 3:
            out.append(f"{where}: the node answered {len(heard['o'])} time(s) on /o and "
                       f"{len(heard['levels'])} on /diagnostics in "
                       f"{GRAPH_WAIT:g} s, expected 3")
        elif set(heard["o"]) != {want}:
            out.append(f"{where}: /o carried {heard['o']}, the Python form decides {want}")
        elif d.fault and set(heard["levels"]) != {2} or not d.fault and 2 in heard["levels"]:
            out.append(f"{where}: /diagnostics levels {heard['levels']}, the Python form's "
                       f"fault: {d.fault!r}")
        elif d.overridden and 0 in heard["levels"]:
            out.append(f"{where}: /diagnostics said OK where the proposal is overridden")
    return out



def _judge_run(n: int, events: list[tuple[str, str, Any, int]], answers: list[dict[str, Any]],
               shield: Any, seen: dict[str, int]) -> list[str]:
    """One run's messages and reports (:func:`check_shield_ros2`) against the Python form
    ``shield``, stepped as the node must be; ``seen`` counts what the run exercised."""
    x: Any = math.nan  # (the last /x read: none yet is unread)
    proposal = False  # (none heard yet: the default message's)
    bus = None  # (the last message on /o)
    ticked = False
    ticks: list[tuple[float, bool]] = []
    for k, ((kind, topic, value, _t), got) in enumerate(zip(events, answers, strict=True)):
        where = f"run {n} message {k} ({kind} {topic} {value!r})"
        sent = [tuple(m) for m in got["sent"]]
        errors = [msg for level, msg in got["diagnostics"] if level == 2]
        if sent:
            bus = sent[-1][1]
        if topic == "/o_proposed":
            if kind == "garbage":
                seen["bytes that are no message"] += 1
                if sent or not any("not read" in e for e in errors):
                    return [f"{where}: sent {sent}, errors {errors}; expected nothing sent "
                            "and an ERROR saying the message was not read"]
                continue
            proposal = value
            if not ticked:
                continue
            before = shield.state
            d = shield.step({"x": x}, {"o": proposal})
            shield.restore(before)
            seen["a proposal corrected between ticks"] += d.outputs["o"] != proposal
            if sent != [("/o", bool(d.outputs["o"]))]:
                return [f"{where}: the node answered {sent}, the Python form decides "
                        f"o = {d.outputs['o']} from the last tick's state"]
            continue
        if kind == "message":  # (a log field's infinity is unread, as the audit reads it)
            x = value if math.isfinite(value) else math.nan
        d = shield.step({"x": x}, {"o": proposal})
        ticked = True
        seen["a tick overridden"] += bool(d.overridden)
        seen["a fault tick"] += bool(d.fault)
        want = bool(d.outputs["o"])
        if bus != want:
            return [f"{where}: after the tick /o holds {bus}, the Python form decides {want}"]
        fault = kind == "garbage" or bool(d.fault)
        if fault != bool(errors):
            return [f"{where}: ERROR reports {errors}, expected "
                    f"{'one' if fault else 'none'} (the Python form's fault: {d.fault!r})"]
        if d.fault and ("/o", want) not in sent:
            return [f"{where}: a fault tick sent {sent}, not the fallback's o = {want}"]
        ticks.append((x, want))
    return _unsafe(n, ticks)


def _unsafe(n: int, ticks: list[tuple[float, bool]]) -> list[str]:
    """Where the commands on the bus after each tick break S1 or S2 by the reference
    evaluator (an unread ``x`` read both ways)."""
    for unread_as in (False, True):
        trace = [{"m": False, "s": False, "r": o,
                  "c": unread_as if math.isnan(x) else x > 5} for x, o in ticks]
        for rid, key in SHIELD_KEYS.items():
            if ref.verdict(key, trace) == "violated":
                return [f"run {n}: {rid} violated by the commands on the bus {ticks}"]
    return []


#: the ``+tick`` plan of every agent: the decision is the machine's (its action shield/4),
#: the beliefs and the published outputs are what it gives
AGENT_PLAN = ("+tick(Tick) : {B mem(State, Was, Broken)} <- shield(State, Out, Next, Now), "
              "-mem(State, Was, Broken), +mem(Next, Out, Now), publish(Out);")
#: random runs and ticks the Java machine is stepped over
JAVA_RUNS = 40
JAVA_TICKS = 12
#: seconds javac or one java run may take
JAVA_TIMEOUT = 300


def _gwendolen_forms(run: Run, name: str) -> Path | list[str]:
    """The check shield's ``--emit gwendolen --emit python`` folder, or the failure of
    ``fretc shield``."""
    folder = _folder(run, name)
    code, text = fretc(run, [*shield_command(folder), "--emit", "gwendolen", "--emit",
                             "python", "-o", str(folder / "out")])
    if code != 0 or not (folder / "out" / "s.gwen").is_file():
        return [f"fretc shield --emit gwendolen exited {code}: {text.strip()[-300:]}"]
    return folder / "out"


def machine_lines(shield: Any, runs: list[list[tuple[dict[str, Any], dict[str, Any]]]]
                  ) -> tuple[list[str], list[str]]:
    """The Python form ``shield`` (a new ``Shield()``) stepped over ``runs`` (each a list of
    ``(inputs, proposal)`` per tick, the shield reset before each): per tick the line the
    Gwendolen form's ``N_shield.java`` ``main`` reads (input atoms, proposed atoms, the state
    before, as 0s and 1s) and the line it must print (decided atoms, the next state, 1 when
    an assumption broke)."""
    machines = shield.machines
    lines, want = [], []
    for run in runs:
        shield.reset()
        for ins, prop in run:
            before = [b for m in machines for b in m.state]
            in_atoms: dict[str, int] = {}
            for m in machines:  # (an input atom several machines read is one percept)
                for spec, f in zip(m.ins, m.in_tests, strict=True):
                    in_atoms[repr(spec)] = int(f(ins))
            prop_atoms = [int(f(prop)) for m in machines for f in m.out_tests]
            d = shield.step(ins, prop)
            out_atoms = [int(f(d.outputs)) for m in machines for f in m.out_tests]
            after = [b for m in machines for b in m.state]
            lines.append(f"{_bits(list(in_atoms.values()))} {_bits(prop_atoms)} "
                         f"{_bits(before)}")
            want.append(f"{_bits(out_atoms)} {_bits(after)} {int(bool(d.broken))}")
    return lines, want


def _java_runs() -> list[list[tuple[dict[str, Any], dict[str, Any]]]]:
    """Seeded random runs of the check shield: ``x`` held from the tick before with
    probability 0.7, proposals random."""
    rnd = random.Random(SEED + 12)
    runs = []
    for _ in range(JAVA_RUNS):
        x, run = 0.0, []
        for _t in range(JAVA_TICKS):
            x = x if rnd.random() < 0.7 else float(rnd.randint(0, 9))
            run.append(({"x": x}, {"o": rnd.random() < 0.35}))
        runs.append(run)
    return runs


def check_shield_gwendolen(run: Run) -> list[str]:
    """The check shield's Gwendolen agent (``--emit gwendolen``): its ``+tick`` plan decides
    with the machine's action and believes what it gives (:data:`AGENT_PLAN`), and the
    machine (``s_shield.java``, built by the JDK's javac) stepped over seeded random runs
    gives at every tick the decided atoms, next state and broken flag of the Python form."""
    javac = shutil.which("javac")
    if javac is None:
        raise CheckSkipped("no javac (a JDK 11 or later) on the PATH: the agent's machine "
                           "cannot be built")
    out = _gwendolen_forms(run, "shield-gwendolen")
    if isinstance(out, list):
        return out
    failures = []
    gwen = (out / "s.gwen").read_text(encoding="utf-8").splitlines()
    if AGENT_PLAN not in gwen or "o :- mem(_, v(1), _);" not in gwen:
        failures.append("the agent's +tick plan or its belief o is not the machine's decision")
    lines, want = machine_lines(_load(out / "s_shield.py").Shield(), _java_runs())
    classes = out / "classes"
    # (no performance data files in the machine's temporary folder: -XX:-UsePerfData)
    built = subprocess.run([javac, "-J-XX:-UsePerfData", "-nowarn", "-d", str(classes),
                            str(out / "s_shield.java")],
                           capture_output=True, text=True, timeout=JAVA_TIMEOUT)
    if built.returncode != 0:
        return failures + [f"javac refused s_shield.java: {built.stderr.strip()[-300:]}"]
    java = str(Path(javac).with_name("java"))
    ran = subprocess.run([java, "-XX:-UsePerfData", "-cp", str(classes), "s_shield"], input="\n".join(lines) + "\n",
                         capture_output=True, text=True, timeout=JAVA_TIMEOUT)
    got = ran.stdout.splitlines()
    if ran.returncode != 0 or len(got) != len(want):
        return failures + [f"the Java machine exited {ran.returncode} with {len(got)} lines "
                           f"for {len(want)} ticks: {ran.stderr.strip()[-300:]}"]
    failures += [f"tick {k} ({lines[k]}): Java {got[k]}, Python {want[k]}"
                 for k in range(len(want)) if got[k] != want[k]]
    if len({w.split()[0] for w in want}) < 2:
        failures.append("the runs never change the decided atoms: they show nothing")
    return _capped(failures)


#: the property AJPF checks in the ``shield-ajpf`` check (``immediately``: stated exactly)
AJPF_PROPERTY = "S1"
#: the belief rule of the agent's output, and the mutant's (o believed when decided false)
AGENT_RULE = "o :- mem(_, v(1), _);"
MUTANT_RULE = "o :- mem(_, v(0), _);"


def check_shield_ajpf(run: Run) -> list[str]:
    """``fretc ajpf`` (AJPF_HOME's MCAPL, AJPF_JAVA's Java 11) on the check shield's agent:
    S1 holds for the agent as generated (exit 0), and an agent that believes ``o`` when the
    machine decided it false gets S1 violated (exit 1), one JPF run each."""
    from fretc.shield.ajpf_run import AjpfRunError, find_tools

    try:
        find_tools(None, None, None)
    except AjpfRunError as exc:
        raise CheckSkipped(f"AJPF cannot run here: {exc}") from None
    out = _gwendolen_forms(run, "shield-ajpf")
    if isinstance(out, list):
        return out
    mutant = out.parent / "mutant"
    shutil.copytree(out, mutant)
    gwen = (out / "s.gwen").read_text(encoding="utf-8")
    if AGENT_RULE not in gwen:
        return [f"the agent has no rule {AGENT_RULE!r}: the mutant cannot be made"]
    (mutant / "s.gwen").write_text(gwen.replace(AGENT_RULE, MUTANT_RULE), encoding="utf-8")
    failures = []
    for folder, code_wanted, word in ((out, 0, "holds"), (mutant, 1, "violated")):
        code, text = fretc(run, ["ajpf", str(folder), "--property", AJPF_PROPERTY,
                                 "--timeout", "600"])
        if code != code_wanted or f"{AJPF_PROPERTY}: {word}" not in text:
            failures.append(f"fretc ajpf on the {'mutated ' if folder == mutant else ''}agent: "
                            f"exit {code}, expected {code_wanted} with {AJPF_PROPERTY} {word}: "
                            f"{text.strip()[-300:]}")
    return failures


CHECKS: tuple[Check, ...] = (
    Check("shield-ros2", ("TOR-SHD-005",),
          "the shield's ROS 2 node (rclpy) message by message against its Python form",
          check_shield_ros2),
    Check("shield-gwendolen", ("TOR-SHD-006",),
          "the Gwendolen agent's Java machine (javac) against the shield's Python form",
          check_shield_gwendolen),
    Check("shield-ajpf", ("TOR-SHD-006",),
          "fretc ajpf: AJPF proves the agent's property, and refutes it on a mutant",
          check_shield_ajpf),
)
