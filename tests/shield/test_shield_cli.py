"""``fretc shield`` on the Safe-ROS requirements and on the requirements it must refuse:
what it enforces, monitors and refuses (exit codes), the forms it writes (deterministic,
standalone), and outputs of one message corrected together."""

from __future__ import annotations

import csv
import io
import itertools
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.shield.emit_python import load_shield, render_python, tables
from fretc.shield.machine import evaluate
from fretc.shield.runtime import ShieldRuntime

from _gen import compile_text

REPO = Path(__file__).resolve().parents[2]
SAFE_ROS = [str(REPO / "requirements" / "safe_ros.fret"), "-b",
            str(REPO / "requirements" / "safe_ros.bindings.toml"), "--inputs",
            "too_close,scan_stale,clearance", "--outputs",
            "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed"]


def shield_cli(*args: str):
    return CliRunner().invoke(main, ["shield", *args])


@pytest.fixture(scope="module")
def safe_ros():
    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements
    from fretc.shield.build import build_shield
    from fretc.signals.bindings.files import load_bindings

    compiled = compile_entries(load_requirements([REPO / "requirements" / "safe_ros.fret"]))
    bindings = load_bindings(REPO / "requirements" / "safe_ros.bindings.toml")
    return compiled, build_shield(compiled, ["too_close", "scan_stale", "clearance"],
                                  ["stopped", "stop_requested", "forwarded_zero",
                                   "linear_speed", "angular_speed"], bindings=bindings,
                                  fork=False, name="safe_ros")


def test_safe_ros_enforces_r2_r3_r4_r6_monitors_r5_and_is_proved(tmp_path):
    got = shield_cli(*SAFE_ROS, "--prove", "--emit", "python", "--emit", "c", "-o",
                     str(tmp_path))
    assert got.exit_code == 0, got.output
    assert "enforces R2, R3, R4, R6" in got.output
    assert "monitored only: R5" in got.output
    for rid in ("R2", "R3", "R4", "R6"):
        assert f"  {rid}: holds" in got.output
    assert "the shield satisfies every enforced requirement" in got.output
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "safe_ros.bindings.toml", "safe_ros_shield.c", "safe_ros_shield.h", "safe_ros_shield.py",
        "safe_ros_shield_run.c"]
    again = tmp_path / "again"
    assert shield_cli(*SAFE_ROS, "--emit", "python", "--emit", "c", "-o", str(again)).exit_code == 0
    for p in again.iterdir():
        assert p.read_bytes() == (tmp_path / p.name).read_bytes(), p.name


def test_the_python_form_runs_on_the_standard_library_alone(tmp_path, safe_ros):
    _compiled, shield = safe_ros
    path = tmp_path / "safe_ros_shield.py"
    path.write_text(render_python(shield), encoding="utf-8")
    code = ("import importlib.util as u, sys\n"
            "s = u.spec_from_file_location('m', sys.argv[1]); m = u.module_from_spec(s)\n"
            "s.loader.exec_module(m)\n"
            "print(sorted(k for k in sys.modules if k.split('.')[0] == 'fretc'))\n"
            "sh = m.Shield()\n"
            "d = sh.step({'too_close': True, 'scan_stale': False, 'clearance': 1.0},\n"
            "            {'stopped': False, 'stop_requested': False, 'forwarded_zero': False,\n"
            "             'linear_speed': 0.9, 'angular_speed': 0.1})\n"
            "print(d.overridden, d.reasons)\n")
    out = subprocess.run([sys.executable, "-I", "-S", "-c", code, str(path)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == ["[]", "True ('R4',)"]


def test_outputs_of_one_message_never_take_values_no_message_gives(safe_ros):
    # stopped, forwarded_zero, linear_speed, angular_speed all read /cmd_vel_filtered:
    # forwarded_zero (every component 0) gives stopped and both speeds within their limits
    _compiled, shield = safe_ros
    (m,) = shield.machines
    texts = [a.text for a in m.outputs]
    fz, st = texts.index("forwarded_zero"), texts.index("stopped")
    lin = texts.index("(linear_speed <= 0.5)")
    for ins in itertools.product((0, 1), repeat=len(m.inputs)):
        for outs in itertools.product((0, 1), repeat=len(m.outputs)):
            if outs[fz] and not (outs[st] and outs[lin]):
                values = list(ins) + list(outs) + [int(b) for b in m.init]
                assert not evaluate(m.nodes, m.safe, values), outs
    rt = ShieldRuntime(tables(shield))
    prop = {"stopped": False, "stop_requested": False, "forwarded_zero": False,
            "linear_speed": 0.4, "angular_speed": 0.1}
    seen = set()
    for t in range(40):
        d = rt.step({"too_close": t >= 3, "scan_stale": t >= 20, "clearance": 1.0}, prop)
        o = d.outputs
        if o["forwarded_zero"]:
            assert o["stopped"] and o["linear_speed"] == 0.0 and o["angular_speed"] == 0.0
        if d.overridden:
            seen.add((t, d.reasons))
    # R2 forces the stop at its deadline (10 ticks after the trigger at tick 3), R6 the stop
    # request 5 ticks after scan_stale (tick 20), with R3's forwarded zero
    assert (13, ("R2",)) in seen and (25, ("R6",)) in seen


def test_an_override_only_the_bindings_force_blames_no_requirement(safe_ros, tmp_path):
    """``forwarded_zero`` proposed without ``stopped`` is no message of /cmd_vel_filtered:
    the shield overrides it, and no requirement is broken by it. The reasons named every
    requirement (R2, R3, R4, R6), which the ROS 2 node's /diagnostics showed as the cause.
    The same tick in C gives the same reasons; a proposal that breaks R4 still names R4."""
    from _c_monitors import build as build_c, needs_cc, write
    from fretc.shield.emit_c import render_c

    _compiled, shield = safe_ros
    ins = {"too_close": False, "scan_stale": False, "clearance": 1.0}
    incoherent = {"stopped": False, "stop_requested": False, "forwarded_zero": True,
                  "linear_speed": 0.0, "angular_speed": 0.0}
    fast = {"stopped": False, "stop_requested": False, "forwarded_zero": False,
            "linear_speed": 0.9, "angular_speed": 0.0}
    (m,) = shield.machines
    texts = [a.text for a in m.outputs]
    assert not evaluate(m.nodes, m.ctl_ok, [0] * len(m.inputs)
                        + [int(t == "forwarded_zero") for t in texts] + list(map(int, m.init)))
    d = ShieldRuntime(tables(shield)).step(ins, incoherent)
    assert d.overridden and d.changed and d.reasons == ()
    d = ShieldRuntime(tables(shield)).step(ins, fast)
    assert d.overridden and d.reasons == ("R4",)
    needs_cc()
    write(render_c(shield, "t"), tmp_path)
    exe = build_c(tmp_path, ["t_shield.c", "t_shield_run.c"], "run")
    names = list(ins) + list(incoherent)

    def row(values: dict) -> str:
        return ",".join(str(v).lower() for v in values.values())

    got = subprocess.run([str(exe)], input=",".join(names) + "\n" + row({**ins, **incoherent})
                         + "\n" + row({**ins, **fast}) + "\n", capture_output=True,
                         text=True, timeout=60)
    assert got.returncode == 0, got.stderr
    rows = list(csv.DictReader(io.StringIO(got.stdout)))
    assert [(r["overridden"], r["reasons"]) for r in rows] == [("1", ""), ("1", "R4")]


def test_a_mutated_shield_fails_its_proof(safe_ros):
    # the proof is not vacuous: a shield letting every move through violates R2
    from dataclasses import replace

    from fretc.shield.prove import prove_shield

    compiled, shield = safe_ros
    (m,) = shield.machines
    loose = replace(shield, machines=(replace(m, safe=m.env_ok),))
    proof = prove_shield(loose, compiled)
    assert not proof.holds and proof.results["R2"] == "violated", proof.text()
    assert "a run of the closed loop violates it" in proof.why["R2"]


@pytest.mark.parametrize("text, args, words", [
    ("R1: whenever a sw shall eventually satisfy x\n", ["--inputs", "a", "--outputs", "x"],
     "give a deadline"),
    ("R1: only in m mode sw shall always satisfy x\n", ["--inputs", "m", "--outputs", "x"],
     "strong until"),
    ("R1: whenever a sw shall immediately satisfy x\n", ["--inputs", "a", "--outputs", "y"],
     "declared neither input nor output"),
    ("R1: whenever a sw shall immediately satisfy x\nR2: whenever a sw shall immediately "
     "satisfy !x\n", ["--inputs", "a", "--outputs", "x"],
     "these inputs, tick by tick, defeat every controller: {a=true}"),
    ("R1: whenever a sw shall immediately satisfy x\n", ["--inputs", "a,x", "--outputs", "x"],
     "declared both input and output"),
    ("R1: whenever x sw shall at the next timepoint satisfy !a\nR2: whenever !x sw shall at "
     "the next timepoint satisfy a\n", ["--inputs", "a", "--outputs", "x"],
     "no fixed input sequence defeats every controller (every one has a matching output "
     "sequence): the environment must react to the outputs"),
])
def test_refusals_are_input_errors_that_say_why(tmp_path, text, args, words):
    f = tmp_path / "r.fret"
    f.write_text(text, encoding="utf-8")
    got = shield_cli(str(f), *args)
    assert got.exit_code == 2, got.output
    assert words in got.output


@pytest.mark.parametrize("op, value, enforced", [
    ("<=", "0.001", False), ("<", "1", False), ("=", "0.5", False), ("!=", "1", False),
    (">=", "0.9", True), (">", "0.5", True), ("=", "1", True), ("<=", "1", True),
])
def test_a_probability_bound_is_enforced_only_where_probability_1_meets_it(tmp_path, op,
                                                                          value, enforced):
    """The shield enforces a requirement's property on every run, so with probability 1:
    a bound that 1 breaks (``<= 0.001``) is refused, the audit of the shielded runs would
    find it failed; one that 1 meets is enforced, with a note."""
    f = tmp_path / "r.fret"
    f.write_text(f"R: if armed the drone shall with probability {op} {value} never satisfy "
                 "motor_fault\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "armed", "--outputs", "motor_fault",
                     "-o", str(tmp_path / "out"))
    if enforced:
        assert got.exit_code == 0, got.output
        assert f"'with probability {op} {value}' is enforced on every run" in got.output
    else:
        assert got.exit_code == 2, got.output
        assert f"bounds the probability of its property by {op} {value}" in got.output


def test_files_of_different_tick_periods_are_refused(tmp_path):
    """Each duration counts ticks of its own file's period and the shield steps on one
    tick: B's 'within 2 seconds' at 1 s a tick was enforced as 2 ticks of 100 ms."""
    (tmp_path / "fast.fret").write_text("@tick_period 100 ms\nA: upon i c shall within 1 "
                                        "second satisfy o\n", encoding="utf-8")
    (tmp_path / "slow.fret").write_text("@tick_period 1 s\nB: upon j c shall within 2 "
                                        "seconds satisfy p\n", encoding="utf-8")
    got = shield_cli(str(tmp_path / "fast.fret"), str(tmp_path / "slow.fret"), "--inputs",
                     "i,j", "--outputs", "o,p", "-o", str(tmp_path / "out"))
    assert got.exit_code == 2, got.output
    assert "requirements of different tick periods: 100 ms: A (" in got.output
    assert "1 s: B (" in got.output
    (tmp_path / "slow.fret").write_text("@tick_period 100 ms\nB: upon j c shall within 2 "
                                        "seconds satisfy p\n", encoding="utf-8")
    got = shield_cli(str(tmp_path / "fast.fret"), str(tmp_path / "slow.fret"), "--inputs",
                     "i,j", "--outputs", "o,p", "-o", str(tmp_path / "out"))
    assert got.exit_code == 0, got.output


def test_over_inputs_only_is_monitored_not_enforced(tmp_path):
    compiled = compile_text("R1: sw shall always satisfy a\nR2: whenever a sw shall "
                            "immediately satisfy x\n", tmp_path)
    from fretc.shield.build import build_shield

    shield = build_shield(compiled, ["a"], ["x"], fork=False)
    assert list(shield.monitored) == ["R1"]
    assert [r.id for r in shield.requirements] == ["R2"]
    sh = load_shield(render_python(shield))()
    assert sh.step({"a": True}, {"x": False}).outputs == {"x": True}


def test_an_unknown_preference_is_refused(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever a sw shall immediately satisfy x | y\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x,y", "--prefer", "z")
    assert got.exit_code == 2 and "--prefer names z" in got.output
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x,y", "--prefer", "!x")
    assert got.exit_code == 0, got.output


@pytest.mark.parametrize("prefer", ["x,!x", "!y, x, y", "x,x"])
def test_an_atom_preferred_twice_is_refused(tmp_path, prefer):
    """``--prefer 'x,!x'`` was accepted, the second silently dead (the first wins)."""
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever a sw shall immediately satisfy x | y\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x,y", "--prefer", prefer)
    assert got.exit_code == 2 and "twice" in got.output, got.output


def test_declared_variables_no_requirement_reads_are_named_in_the_notes(tmp_path):
    """An input or output read by no requirement (a typo beside the right name, a variable
    left over) was accepted without a word."""
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever a sw shall immediately satisfy x\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "a,zz", "--outputs", "x,yy")
    assert got.exit_code == 0, got.output
    assert "note: zz: declared an input, read by no requirement (not used)" in got.output
    assert ("note: yy: declared an output, read by no requirement (passed through "
            "unchanged)") in got.output
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x")
    assert got.exit_code == 0 and "read by no requirement" not in got.output


def test_the_query_cpu_the_budget_message_names_is_an_option_of_shield(tmp_path,
                                                                     monkeypatch):
    """A game past its CPU limit said "(--query-cpu)", an option only fretc check had."""
    import inspect

    from fretc.check.solver import SpotWorker  # (the message's source)
    from fretc.shield import build

    assert "(--query-cpu)" in inspect.getsource(SpotWorker)
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever a sw shall immediately satisfy x\n", encoding="utf-8")
    budgets = []
    real = build.build_shield

    def spy(*args, **kw):
        budgets.append(kw["budget"])
        return real(*args, **kw)

    monkeypatch.setattr(build, "build_shield", spy)
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x", "--query-cpu", "30")
    assert got.exit_code == 0, got.output
    assert [b.cpu for b in budgets] == [30]
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x", "--query-cpu", "0")
    assert got.exit_code == 2 and "--query-cpu" in got.output


def test_explain_says_what_r2_permits_and_what_r7_takes_away(tmp_path):
    got = shield_cli(*SAFE_ROS, "--explain")
    assert got.exit_code == 0, got.output
    assert ("R2: stopped may wait up to 10 ticks (1 s) after too_close becomes true; once it "
            "holds, stopped may stop holding again while too_close still holds") in got.output
    assert "R3: forwarded_zero must hold at every tick at which stop_requested holds" \
        in got.output
    assert "R6: stop_requested may wait up to 5 ticks (0.5 s)" in got.output
    stay = str(REPO / "requirements" / "shield" / "stay_stopped.fret")
    got = shield_cli(SAFE_ROS[0], stay, *SAFE_ROS[1:], "--explain")
    assert got.exit_code == 0, got.output
    assert "R2: stopped must hold at once after too_close becomes true" in got.output
    assert "R2: stopped may stop holding" not in got.output


@pytest.mark.parametrize("text, why", [
    ("A: upon i1 c shall for 3 ticks satisfy o1\n", "the 'for' timing"),
    ("A: in i2 mode c shall always satisfy o1\n", "the 'in' scope"),
    ("A: upon i1 c shall until i2 satisfy o1\n", "the 'until' timing"),
    ("A: upon i1 c shall at the next timepoint satisfy o1\n", "the 'next' timing"),
    ("A: upon i1 c shall always satisfy o1\n", "the 'always' timing"),
])
def test_explain_reads_no_liberty_off_a_scope_or_a_timing_of_more_than_one_response(
        tmp_path, text, why):
    """--explain's wait and release describe one response after the condition: for a
    scope or another timing they said what the shield does not allow (``for 3 ticks``:
    "may stop holding again"; a mode: "may never come")."""
    f = tmp_path / "r.fret"
    f.write_text(text, encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "i1,i2", "--outputs", "o1", "--explain")
    assert got.exit_code == 0, got.output
    assert f"A: enforced as it reads ({why}); its liberties are not read here" in got.output
    assert "may stop holding" not in got.output and "may never come" not in got.output


def test_a_margin_meets_each_deadline_early_and_is_refused_past_one(tmp_path):
    got = shield_cli(*SAFE_ROS, "--margin", "1", "--explain", "--prove")
    assert got.exit_code == 0, got.output
    assert "R2: stopped may wait up to 9 ticks (0.9 s)" in got.output
    assert "  R2: holds" in got.output  # the original deadline, proved
    f = tmp_path / "r.fret"
    f.write_text("R1: upon a sw shall within 2 ticks satisfy x\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "a", "--outputs", "x", "--margin", "3")
    assert got.exit_code == 2 and "shorter than the margin of 3" in got.output, got.output


@pytest.mark.parametrize("text, args", [
    ("A: the c shall always satisfy y > 1 & y < 1.0000000000000002\n", ["--outputs", "y"]),
    ("A: whenever i1 c shall immediately satisfy y > 0.1 & y < 0.10000000000000001\n",
     ["--inputs", "i1", "--outputs", "y"]),
])
def test_a_region_with_reals_and_no_double_is_no_move(tmp_path, text, args):
    """The shield decides in doubles: a response whose values lie between two constants
    with no double between them (two literals that are one double) cannot be met; it was
    synthesized over the reals, and then the Python form raised and the C form gave NaN
    as the correction. Refused, saying why ``fretc check`` (over the reals) differs."""
    f = tmp_path / "r.fret"
    f.write_text(text, encoding="utf-8")
    got = shield_cli(str(f), *args, "-o", str(tmp_path / "out"))
    assert got.exit_code == 2, got.output
    assert "in doubles as the shield decides: the comparisons of y have values" in got.output
    assert "fretc check gives the same finding" not in got.output
    f.write_text(text.replace("1.0000000000000002", "1.5").replace("0.10000000000000001",
                                                                   "0.3"), encoding="utf-8")
    assert shield_cli(str(f), *args, "-o", str(tmp_path / "out")).exit_code == 0


def test_a_cluster_valuation_whose_numbers_fail_in_doubles_is_never_chosen(tmp_path):
    """z3's numbers for ``y + z = 0.3 & y = 0.1`` are 0.1 and 0.2, whose double sum is not
    0.3: an internal error (exit 4) before. The valuation is never chosen, and the set,
    realizable over the reals, is refused as the shield decides (in doubles), saying so."""
    f = tmp_path / "r.fret"
    f.write_text("A: the c shall always satisfy y + z = 0.3\n"
                 "B: whenever i1 c shall immediately satisfy y = 0.1\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "i1", "--outputs", "y,z", "-o", str(tmp_path / "a"))
    assert got.exit_code == 2, got.output
    assert "((y + z) = 0.3) & (y = 0.1) (z3's numbers" in got.output
    assert "never chosen, where fretc check, over the reals, counts it" in got.output


def test_unrealizable_inputs_name_dotted_and_quoted_variables(tmp_path):
    """The inputs that defeat every controller are read from Spot's letters, which name a
    variable as FRET mangles it (``a.b`` is ``a_DOT_b``): a dotted input was left out
    (``{a_b=true}``: with ``a.b`` false the controller wins). A quoted name with a space is
    declared with its quotes (it could not be)."""
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever a.b c shall immediately satisfy o\n"
                 "R2: whenever a_b c shall immediately satisfy !o\n", encoding="utf-8")
    got = shield_cli(str(f), "--inputs", "a.b,a_b", "--outputs", "o")
    assert got.exit_code == 2 and "defeat every controller: {a.b=true, a_b=true}" in got.output
    f.write_text('R1: whenever "weird var" c shall immediately satisfy o\n'
                 'R2: whenever "weird var" c shall immediately satisfy !o\n', encoding="utf-8")
    got = shield_cli(str(f), "--inputs", '"weird var"', "--outputs", "o")
    assert got.exit_code == 2 and "defeat every controller: {weird var=true}" in got.output


def test_an_output_folder_that_cannot_be_made_is_a_usage_error(tmp_path):
    """``-o /dev/null`` (an existing file that is no folder) was an internal error (exit 4).

    fretc's behaviour is asserted, not whose words refuse it: click's ``Path(file_okay=False)``
    answers first where ``/dev/null`` stats as a regular file or in a click release that checks
    more ("Directory '/dev/null' is a file"), fretc's own check otherwise. Either way: a usage
    error (exit 2) that names the folder, nothing written, no traceback. A regular file as
    ``-o`` is the same case on every machine."""
    plain = tmp_path / "plain-file"
    plain.write_text("kept\n")
    for target in ("/dev/null", str(plain)):
        got = shield_cli(*SAFE_ROS, "--emit", "python", "-o", target)
        assert got.exit_code == 2, got.output
        assert target in got.output.replace("\n", ""), got.output
        assert "Traceback" not in got.output
    assert plain.read_text() == "kept\n"


def test_unrealizable_only_as_messages_says_so_and_not_that_check_agrees(tmp_path):
    """``a = /cmd.x > 0`` and ``b = /cmd.x < 0``: no message gives ``a & b``, so the shield
    with the bindings has no controller where ``fretc check`` (no bindings) finds one; the
    refusal said "fretc check gives the same finding"."""
    (tmp_path / "m.fret").write_text(
        "@inputs go\n@outputs a, b\nR1: whenever go ctrl shall immediately satisfy a & b\n")
    (tmp_path / "m.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\n[variables]\ngo = "/go.data"\na = "/cmd.x > 0"\n'
        'b = "/cmd.x < 0"\n')
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "m.fret"), "-b",
                                    str(tmp_path / "m.bindings.toml")])
    assert got.exit_code == 2, got.output
    assert "valuations of a, b that no message of /cmd gives are never chosen" in got.output
    assert "fretc check gives the same finding" not in got.output
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "m.fret")])
    assert got.exit_code == 0, got.output
