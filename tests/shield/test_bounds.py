"""Outputs bounded by functions of the inputs and of the proposal (fretc.check.bounds,
fretc.shield.runtime_bounds): Nav2's collision monitor's speed proportional to the free
distance, time before collision and slowdown to a share of the command, enforced and proved,
in the Python, C and ROS 2 (MessageShield) forms; the runtime's number against an independent
solver (z3 over the reals, and the compiler's reference evaluator in doubles); twists scaled
together, the path's curvature kept (docs/guide/shield.md, "Speed and separation")."""

from __future__ import annotations

import csv
import io
import math
import subprocess
from fractions import Fraction
from functools import cache
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.compiler.build import compile_entries
from fretc.compiler.evaluate import pt_at
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import load_shield, render_python, tables
from fretc.shield.plan import ShieldError
from fretc.shield.runtime import ShieldRuntime
from fretc.shield.twists import twists_of

from _c_monitors import build, needs_cc, write
from _gen import compile_text

REPO = Path(__file__).resolve().parents[2]
FRET = REPO / "requirements" / "shield" / "speed_separation.fret"
BINDINGS = REPO / "requirements" / "shield" / "speed_separation.bindings.toml"
INPUTS = ["front_dist", "proposed_velocity", "in_slowdown"]
OUTPUTS = ["linear_velocity", "angular_velocity"]
TYPES = {"/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist",
         "/cmd_vel_filtered": "geometry_msgs/msg/Twist"}
#: bounds both ways at once: the upper ones of the shipped file, a lower one near an obstacle
#: and a floor beyond 0.3 m (realizable: the conditions keep them apart); P2 and P4 divide by
#: their factors, so their thresholds are not their bounds' values in doubles
BOTH_WAYS = """@inputs d, p, s
@outputs v
P1: whenever s sw shall immediately satisfy v <= 0.5 * (d - 0.3)
P2: sw shall always satisfy 1.5 * v <= d
P3: whenever s & p >= 0 sw shall immediately satisfy v <= 0.3 * p
P4: whenever d > -10.0 & d < 5.0 sw shall immediately satisfy 3.0 * v >= d - 10.0
P5: whenever d > 0.3 sw shall immediately satisfy v > -20.0
"""


@cache
def shipped():
    """The shield of requirements/shield/speed_separation.fret with its bindings and twist,
    and its requirements compiled."""
    from fretc.signals.bindings.files import load_bindings

    compiled = compile_entries(load_requirements([FRET]))
    return build_shield(compiled, INPUTS, OUTPUTS, fork=False, bindings=load_bindings(BINDINGS),
                        twists=twists_of(BINDINGS)), compiled


@cache
def both_ways():
    """The shield of :data:`BOTH_WAYS` and its requirements compiled."""
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        compiled = compile_text(BOTH_WAYS, Path(folder))
    return build_shield(compiled, ["d", "p", "s"], ["v"], fork=False), compiled


def test_the_three_rules_are_enforced_as_nav2_bounds_the_speed():
    """A speed proportional to the free distance (1.1 m ahead: 0.4 m/s), a slowdown to
    30 % of the command (0.3 m/s at 0.9 m: 0.09), a time before collision of 1.5 s
    (0.3 m ahead: the largest speed covering at most 0.3 m in 1.5 s, in doubles: 1.5 * 0.2
    is above 0.3); the most restrictive wins; a proposal that keeps them all passes."""
    shield, _c = shipped()
    rt = ShieldRuntime(tables(shield))
    far = {"front_dist": 3.0, "proposed_velocity": 0.4, "in_slowdown": False}
    assert rt.step(far, {"linear_velocity": 0.4, "angular_velocity": 0.1}).outputs == \
        {"linear_velocity": 0.4, "angular_velocity": 0.1}
    d = rt.step({**far, "front_dist": 1.1}, {"linear_velocity": 0.6, "angular_velocity": 0.0})
    assert d.outputs["linear_velocity"] == 0.5 * (1.1 - 0.3) and d.reasons == ("S1",)
    d = rt.step({"front_dist": 0.9, "proposed_velocity": 0.3, "in_slowdown": True},
                {"linear_velocity": 0.3, "angular_velocity": 0.0})
    assert d.outputs["linear_velocity"] == 0.3 * 0.3 and d.reasons == ("S3",)
    # (S1 is the tighter of S1 and S2 ahead of the robot; S2 alone, time before collision:)
    _s, compiled = shipped()
    alone = build_shield([c for c in compiled if c.id == "S2"], INPUTS, OUTPUTS, fork=False)
    d = ShieldRuntime(tables(alone)).step({**far, "front_dist": 0.3},
                                          {"linear_velocity": 0.6, "angular_velocity": 0.0})
    v = d.outputs["linear_velocity"]
    assert 1.5 * v <= 0.3 < 1.5 * math.nextafter(v, 1.0) and d.reasons == ("S2",)


def test_a_twist_keeps_its_curvature_where_nav2s_limit_would():
    """x=0.349 z=-0.434 inside the slowdown zone: Nav2's limit scales both speeds by one
    factor; the angular speed was kept (z/x grew from -1.24 to -4.15, a tighter turn). Now
    both are scaled by 0.3 and the decision says so; the curvature is the proposal's."""
    shield, _c = shipped()
    rt = ShieldRuntime(tables(shield))
    d = rt.step({"front_dist": 0.8, "proposed_velocity": 0.349, "in_slowdown": True},
                {"linear_velocity": 0.349, "angular_velocity": -0.434})
    x, z = d.outputs["linear_velocity"], d.outputs["angular_velocity"]
    assert x == 0.3 * 0.349 and z == pytest.approx(-0.434 * 0.3, rel=1e-12)
    assert z / x == pytest.approx(-0.434 / 0.349, rel=1e-12)
    assert d.scaled and "linear_velocity, angular_velocity scaled by" in d.scaled[0]
    # (a correction that is no slowdown, backing away within 0.3 m, is not scaled)
    d = rt.step({"front_dist": 0.2, "proposed_velocity": 0.3, "in_slowdown": True},
                {"linear_velocity": 0.3, "angular_velocity": 0.2})
    assert d.outputs["linear_velocity"] < 0 and d.outputs["angular_velocity"] == 0.2
    assert not d.scaled


def test_a_twist_is_not_scaled_where_the_requirements_forbid_it(tmp_path):
    """Turning at least 0.4 rad/s to the right (w < -0.4) is required: scaled, -0.434
    would become -0.13; the angular speed keeps its own correction (none) instead."""
    compiled = compile_text("T1: sw shall always satisfy v <= 0.3 * p\n"
                            "T2: sw shall always satisfy w < -0.4\n", tmp_path)
    shield = build_shield(compiled, ["p"], ["v", "w"], fork=False, twists=[["v", "w"]])
    d = ShieldRuntime(tables(shield)).step({"p": 0.349}, {"v": 0.349, "w": -0.434})
    assert d.outputs == {"v": 0.3 * 0.349, "w": -0.434} and not d.scaled


def test_a_bound_no_finite_number_meets_is_a_fault_with_the_fallbacks_number():
    """REP 117's -inf ("too close to measure") ahead: no finite speed meets 0.5 * (-inf -
    0.3); the speed is the fallback's (rest), and the decision says why. A NaN distance: the
    input is any value (decided for every value it could have had), its bounds cannot be
    computed: the number nearest the fallback's."""
    shield, _c = shipped()
    rt = ShieldRuntime(tables(shield))
    d = rt.step({"front_dist": -math.inf, "proposed_velocity": 0.4, "in_slowdown": True},
                {"linear_velocity": 0.4, "angular_velocity": 0.0})
    assert d.outputs["linear_velocity"] == 0.0 and d.overridden
    assert d.fault.startswith("bound linear_velocity: no finite number gives")
    d = rt.step({"front_dist": math.nan, "proposed_velocity": 0.4, "in_slowdown": False},
                {"linear_velocity": 0.4, "angular_velocity": 0.0})
    assert d.outputs["linear_velocity"] == 0.0
    assert d.fault.startswith("input front_dist is NaN") and "bound linear_velocity" in d.fault
    # (an infinite bound read as the reals read it: 1.5 * v overflows to -inf below -1.2e308,
    # where 1.5 * v <= -inf holds in doubles; no such speed is given)
    d = ShieldRuntime(tables(approach_alone())).step(
        {"front_dist": -math.inf, "proposed_velocity": 0.4, "in_slowdown": False},
        {"linear_velocity": 0.4, "angular_velocity": 0.0})
    assert d.outputs["linear_velocity"] == 0.0 and d.fault.startswith("bound ")


def _z3(n, values: dict, z3):
    """The IR term or comparison ``n`` over the reals (z3), variables at ``values``
    (exact rationals of doubles, or z3 variables): the test's own reading, not fretc's."""
    if n.op == "cmp":
        a, b = (_z3(x, values, z3) for x in n.args)
        op = n.name
        return {"<": a <= b, "<=": a <= b, ">": a >= b, ">=": a >= b}[op]  # (closures)
    if n.op == "var":
        return values[n.name]
    if n.op == "num":
        return z3.RealVal(str(Fraction(n.name)))
    if n.op == "neg":
        return -_z3(n.args[0], values, z3)
    a, b = (_z3(x, values, z3) for x in n.args)
    return {"+": a + b, "-": a - b, "*": a * b, "/": a / b}[n.name]


def _nearest_real(atoms, decided, inputs: dict, p: float):
    """The least distance from ``p`` of a real value of the output ``v`` giving the decided
    truth of each atom (their closures), by z3's optimizer; None when none does."""
    import z3

    v = z3.Real("v")
    values = {k: z3.RealVal(str(Fraction(x))) for k, x in inputs.items()}
    values["v"] = v
    opt = z3.Optimize()
    for a, want in zip(atoms, decided):
        c = _z3(a, values, z3)
        if not want:  # (the other half-line's closure)
            x, y = c.arg(0), c.arg(1)
            c = x >= y if c.decl().kind() == z3.Z3_OP_LE else x <= y
        opt.add(c)
    t = z3.Real("t")
    pv = z3.RealVal(str(Fraction(p)))
    opt.add(t >= v - pv, t >= pv - v)
    opt.minimize(t)
    if opt.check() != z3.sat:
        return None
    return Fraction(str(opt.model().eval(t, model_completion=True)))


_finite = st.floats(-50.0, 50.0, allow_nan=False)
_edge = st.sampled_from([0.0, 0.3, 0.30000000000000004, 5.0, -0.3, 1.5, 10.0, 0.1, -10.0])


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(d=st.one_of(_finite, _edge), p=st.one_of(_finite, _edge), s=st.booleans(),
       v=st.one_of(_finite, _edge))
@example(d=0.3, p=0.3, s=True, v=0.3)
@example(d=4.9, p=-1.0, s=False, v=-30.0)
def test_the_runtimes_number_is_the_nearest_an_independent_solver_finds(d, p, s, v):
    """On random inputs and proposals (bounds both ways at once): the number the runtime
    chooses gives every comparison the machine decided (judged by the compiler's reference
    evaluator, in doubles), the next double towards the proposal does not (no nearer number
    does), and its distance from the proposal is z3's least distance over the reals (to a
    few doubles' rounding)."""
    shield, compiled = both_ways()
    rt = ShieldRuntime(tables(shield))
    m = shield.machines[0]
    atoms = {a.text: n for c in compiled for n in _walk_cmps(c.formalization.pt)
             for a in m.outputs if a.text == _smv(n)}
    ins = {"d": d, "p": p, "s": s}
    dec = rt.step(ins, {"v": v})
    assume(not dec.fault)
    got = dec.outputs["v"]
    nodes = [atoms[a.text] for a in m.outputs]
    decided = [bool(pt_at(n, [{**ins, "v": v}], 0)) != (a.text in dec.changed)
               for a, n in zip(m.outputs, nodes)]
    assert [bool(pt_at(n, [{**ins, "v": got}], 0)) for n in nodes] == decided
    if got != v:
        nearer = math.nextafter(got, v)
        assert [bool(pt_at(n, [{**ins, "v": nearer}], 0)) for n in nodes] != decided
    best = _nearest_real(nodes, decided, ins, v)
    assert best is not None
    dist = abs(Fraction(got) - Fraction(v))
    slack = Fraction(8 * math.ulp(max(abs(got), abs(v), abs(d), abs(p), 1.0)))
    assert best - slack <= dist <= best + slack, (got, float(best))


def _walk_cmps(f):
    from fretc.compiler import ir

    return [n for n in ir.walk(f) if n.op == "cmp"]


def _smv(n) -> str:
    from fretc.compiler.printers import to_smv

    return to_smv(n)


def _csv_rows(rows, inputs: list[str], outputs: list[str]) -> str:
    cols = [*inputs, *outputs]
    out = [",".join(cols)]
    for ins, prop in rows:
        vals = [ins[c] for c in inputs] + [prop[c] for c in outputs]
        out.append(",".join(("true" if x else "false") if isinstance(x, bool)
                            else repr(float(x)) for x in vals))
    return "\n".join(out) + "\n"


_EDGE = [0.0, 0.2, 0.3, 0.30000000000000004, 0.8, 1.0, -0.2, -10.0, 5.0, math.inf, -math.inf,
         math.nan, 1e308, -1e308]


def _shipped_rows(rnd) -> list[tuple[dict, dict]]:
    rows = []
    for _ in range(2000):
        d = rnd.choice(_EDGE) if rnd.random() < 0.3 else rnd.uniform(-0.5, 3.0)
        lv = rnd.uniform(-1, 1) if rnd.random() < 0.9 else rnd.choice(_EDGE)
        av = rnd.uniform(-1, 1) if rnd.random() < 0.9 else rnd.choice(_EDGE)
        pv = lv if rnd.random() < 0.5 else rnd.uniform(-1, 1)
        rows.append(({"front_dist": d, "proposed_velocity": pv,
                      "in_slowdown": rnd.random() < 0.5},
                     {"linear_velocity": lv, "angular_velocity": av}))
    return rows


def _both_ways_rows(rnd) -> list[tuple[dict, dict]]:
    rows = []
    for _ in range(2000):
        # (no NaN distance: this shield has no fallback, and its machine would be lost)
        d = rnd.choice(_EDGE[:-3] + _EDGE[-2:]) if rnd.random() < 0.3 else \
            rnd.uniform(-15.0, 15.0)
        v = rnd.uniform(-30, 30) if rnd.random() < 0.9 else rnd.choice(_EDGE)
        p = v if rnd.random() < 0.5 and not math.isnan(v) else rnd.uniform(-5, 5)
        rows.append(({"d": d, "p": p, "s": rnd.random() < 0.5}, {"v": v}))
    return rows


@cache
def approach_alone():
    """The shield of S2 alone (time before collision: its bound overflows at -inf)."""
    _s, compiled = shipped()
    return build_shield([c for c in compiled if c.id == "S2"], INPUTS, OUTPUTS, fork=False,
                        twists=twists_of(BINDINGS))


@pytest.mark.parametrize("which", ["shipped", "both ways", "approach alone"])
def test_the_c_form_decides_as_the_python_form_tick_by_tick(tmp_path, which):
    """The C form (strict flags, AddressSanitizer and UBSan) of the shipped shield, of
    bounds both ways (strict comparisons, thresholds upwards) and of the approach rule alone
    (``1.5 * v <= -inf`` holds in doubles by overflow) over 2,000 random ticks with infinite,
    NaN and tied distances and proposals: every output, the override and the fault as the
    Python form's."""
    import random

    needs_cc()
    shield = {"shipped": shipped()[0], "both ways": both_ways()[0],
              "approach alone": approach_alone()}[which]
    ins, outs = (["d", "p", "s"], ["v"]) if which == "both ways" else (INPUTS, OUTPUTS)
    write(render_c(shield, "t"), tmp_path)
    exe = build(tmp_path, ["t_shield.c", "t_shield_run.c"], "run")
    rows = (_both_ways_rows if which == "both ways" else _shipped_rows)(random.Random(7))
    got = subprocess.run([str(exe)], input=_csv_rows(rows, ins, outs), capture_output=True,
                         text=True, timeout=120)
    assert got.returncode == 0 and not got.stderr, got.stderr
    rt = ShieldRuntime(tables(shield))
    faults = set()
    for (i, prop), c in zip(rows, csv.DictReader(io.StringIO(got.stdout)), strict=True):
        d = rt.step(i, prop)
        for v in outs:
            want, have = d.outputs[v], float(c[v])
            assert want == have or (math.isnan(want) and math.isnan(have)), (i, prop, d, c)
        kind = "" if not d.fault else "input" if d.fault.startswith("input ") else \
            d.fault.split(" ")[0]
        assert (c["overridden"], c["fault"]) == (str(int(d.overridden)), kind), (d, c)
        faults.add(kind)
    assert faults >= ({"", "bound", "proposal"} if which == "both ways"
                      else {"", "input", "bound", "proposal"})  # (every case met)


def test_the_ros2_form_reads_the_proposal_and_publishes_one_scaled_twist():
    """MessageShield (the ROS 2 node's and shield-replay's): the proposal's value is an
    input bound to the proposal topic (``proposed_velocity = "/cmd_vel.linear.x"``), read
    from the controller's message; the corrected Twist is the proposal's with both speeds
    scaled (x=0.349 z=-0.434 -> 0.1047, -0.1302), read back through the bindings."""
    import numpy as np
    from rosbags.typesys import Stores, get_typestore

    from fretc.shield.messages import MessageShield, default_message
    from fretc.signals.bindings.files import load_bindings

    shield, _c = shipped()
    store = get_typestore(Stores.ROS2_JAZZY)
    ms = MessageShield(load_shield(render_python(shield))(), load_bindings(BINDINGS),
                       {"/cmd_vel_filtered": "/cmd_vel"},
                       lambda topic: default_message(store, TYPES[topic]))
    seen = []
    for k, (r, lx, az) in enumerate([(3.0, 0.4, 0.2), (0.8, 0.349, -0.434), (math.inf, 0.4, 0.1),
                                     (0.5, 0.4, 0.3)]):
        t = (k + 1) * 100_000_000
        scan = default_message(store, TYPES["/scan"])
        scan.angle_min, scan.angle_increment = -math.pi, 2 * math.pi / 360
        scan.range_min, scan.range_max = 0.05, 10.0
        scan.ranges = np.full(360, r, dtype="float32")
        ms.hear("/scan", scan, t)
        cmd = default_message(store, TYPES["/cmd_vel"])
        cmd.linear.x, cmd.angular.z = lx, az
        ms.hear("/cmd_vel", cmd, t)
        d, msgs = ms.tick(t)
        (topic, out), = msgs
        assert topic == "/cmd_vel_filtered"
        assert (out.linear.x, out.angular.z) == (d.outputs["linear_velocity"],
                                                 d.outputs["angular_velocity"])
        seen.append((out.linear.x, out.angular.z, bool(d.scaled)))
    assert seen[0] == (0.4, 0.2, False) and seen[2] == (0.4, 0.1, False)
    assert seen[1][0] == 0.3 * 0.349 and seen[1][1] == pytest.approx(-0.1302, rel=1e-12)
    assert seen[1][2] and seen[3][2]  # (inside 0.5 m: S1's 0.1 m/s, the turn scaled by 1/4)
    assert seen[3][0] == pytest.approx(0.1) and seen[3][1] == pytest.approx(0.075)


def test_fretc_shield_generates_and_proves_it_in_every_form(tmp_path):
    """The guide's command: the shield of the three rules, proved on its closed loop with the
    runtime's choice stated, written as Python, C and a ROS 2 package."""
    got = CliRunner().invoke(main, ["shield", str(FRET), "-b", str(BINDINGS), "--prove",
                                    "--emit", "python", "--emit", "c", "--emit", "ros2",
                                    "-o", str(tmp_path)])
    assert got.exit_code == 0, got.output
    for rid in ("S1", "S2", "S3"):
        assert f"  {rid}: holds" in got.output
    assert "assumes of the runtime's choice: each tick linear_velocity takes a number" \
        in got.output
    assert "one twist: linear_velocity, angular_velocity" in got.output
    assert (tmp_path / "speed_separation_shield.c").exists()
    assert (tmp_path / "speed_separation_shield_ros2" / "speed_separation_shield_ros2"
            / "shield_node.py").exists()


def test_fretc_check_reads_the_same_atoms(tmp_path):
    """``fretc check`` decides the shipped set realizable with the same atoms."""
    got = CliRunner().invoke(main, ["check", str(FRET), "-b", str(BINDINGS), "--json"])
    assert got.exit_code == 0, got.output
    assert '"realizable": true' in got.output


@pytest.mark.parametrize("text, why", [
    ("R1: sw shall always satisfy v <= 0.3 * p\nR2: sw shall always satisfy v != 0.5\n",
     "R1 (.*): v is bounded by the inputs and compared by (v != 0.5)"),
    ("R1: sw shall always satisfy v <= 0.3 * p\nR2: sw shall always satisfy v < w\n",
     "v is bounded by the inputs and compared with other outputs"),
])
def test_a_bounded_output_the_shield_cannot_take_is_refused_with_why(tmp_path, text, why):
    compiled = compile_text(text, tmp_path)
    with pytest.raises(ShieldError, match=why.replace("(v", r"\(v").replace("5)", r"5\)")):
        build_shield(compiled, ["p"], ["v", "w"], fork=False)


def test_twists_are_checked_and_their_errors_name_where_they_are(tmp_path):
    b = tmp_path / "b.bindings.toml"
    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\nv = "/c.x"\n[shield]\n'
                 'twists = [["v"]]\n', encoding="utf-8")
    with pytest.raises(ShieldError, match=r"b\.bindings\.toml:6:1: \[shield\] twists must"):
        twists_of(b)
    compiled = compile_text("R1: sw shall always satisfy v <= 0.3 * p\n", tmp_path)
    with pytest.raises(ShieldError, match="names w, not an output"):
        build_shield(compiled, ["p"], ["v"], fork=False, twists=[["v", "w"]])
    # (the command names the key's file, line and column; exit 2)
    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\np = "/p.data"\nv = "/c.x"\n'
                 '[shield]\ntwists = [["v", "w"]]\n', encoding="utf-8")
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "reqs.fret"), "-b", str(b),
                                    "--inputs", "p", "--outputs", "v"])
    assert got.exit_code == 2 and "b.bindings.toml:7:1: [shield] twists: [v, w] names w, " \
        "not an output (v)" in " ".join(got.output.split()), got.output
    with pytest.raises(ShieldError, match="is named twice"):
        build_shield(compiled, ["p"], ["v", "w"], fork=False, twists=[["v", "w"], ["w", "v"]])
    from fretc.signals.bindings.files import load_bindings

    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\nv = "/c.linear.x"\n'
                 'w = "/c.angular.z"\nspeed = "abs(/c.angular.z)"\n', encoding="utf-8")
    two = compile_text("R1: sw shall always satisfy v <= 0.3 * p & speed <= 0.5\n", tmp_path,
                       "t.fret")
    with pytest.raises(ShieldError, match=r"w reads /c\.angular\.z, which the output speed "
                                          r"reads too \(.*b\.bindings\.toml:6\)"):
        build_shield(two, ["p"], ["v", "w", "speed"], fork=False, bindings=load_bindings(b),
                     twists=[["v", "w"]])
    clustered = compile_text("R1: sw shall always satisfy w < u\n", tmp_path, "c.fret")
    with pytest.raises(ShieldError, match="R1 .*: w is in a twist and compared with other "
                                          "outputs"):
        build_shield(clustered, [], ["w", "u"], fork=False, twists=[["w", "u"]])


def test_a_bounded_output_sharing_its_field_with_another_output_is_refused(tmp_path):
    """``linear_velocity`` bounded by the distance beside Safe-ROS's ``stopped`` and
    ``linear_speed = abs(linear.x)``: the game would choose their comparisons of the one
    number apart from the bound's (a speed above 0.15 with a velocity held below 0.08); the
    shield refuses it, naming the bound's requirement, the other output and the field."""
    from fretc.signals.bindings.files import load_bindings

    b = tmp_path / "b.bindings.toml"
    b.write_text('[tick]\nperiod = "100 ms"\n[variables]\nd = "/d.data"\n'
                 'linear_velocity = "/c.linear.x"\nlinear_speed = "abs(/c.linear.x)"\n',
                 encoding="utf-8")
    compiled = compile_text("R4: sw shall always satisfy linear_speed <= 0.5\n"
                            "A1: sw shall always satisfy linear_velocity <= 0.5 * (d - 0.3)\n",
                            tmp_path)
    with pytest.raises(ShieldError, match=r"A1 \(.*\): linear_velocity is bounded by the "
                                          r"inputs and reads /c\.linear\.x, which the output "
                                          r"linear_speed reads too \(.*b\.bindings\.toml:6\)"):
        build_shield(compiled, ["d"], ["linear_velocity", "linear_speed"], fork=False,
                     bindings=load_bindings(b))
    # (without bindings the two are two numbers, and the shield is made)
    build_shield(compiled, ["d"], ["linear_velocity", "linear_speed"], fork=False)
