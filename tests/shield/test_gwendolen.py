"""``fretc shield --emit gwendolen``: the shipped Safety System (the docs' command) as a
Gwendolen agent that decides with the shield's machine (``N_shield.java``, its action
``shield/4``), and its AJPF properties (``N.psl``: ``immediately`` exact, deadlines stated
without their count and said so, the release of each stop output).

The Java machine is stepped against the Python form over the same seeded random runs of
inputs and proposals (one JVM for every tick, each line given the Python form's state before
the tick, and the Java machine's next state compared with the Python form's): the agent holds
and releases the stop exactly as the Python, C and ROS 2 forms do. AJPF itself runs in
``tests/shield/test_ajpf_agent.py`` (long)."""

from __future__ import annotations

import random
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.qualification.checks_shield import machine_lines
from fretc.shield.emit_python import load_shield

REPO = Path(__file__).resolve().parents[2]
REQS = REPO / "requirements"
NO_JAVAC = "javac is missing: the Gwendolen form's Java cannot be compiled here"

#: the docs' command (docs/guide/shield.md, "Safe-ROS end to end"), the forms this file reads
DOCS_SHIELD = [str(REQS / "safe_ros.fret"), str(REQS / "shield" / "release.fret"),
               "-b", str(REQS / "shield" / "safe_ros_shield.bindings.toml"),
               "--inputs", "too_close,scan_stale,clearance,obstacle_ahead,obstacle_behind",
               "--outputs", "stopped,stop_requested,forwarded_zero,linear_speed,angular_speed,"
               "linear_velocity"]


def write_docs_forms(folder: Path, *extra: str) -> Path:
    """The docs' shield written by ``fretc shield ... --emit python --emit gwendolen -o
    folder`` (``extra``: more options, e.g. ``--assume FILE``)."""
    got = CliRunner().invoke(main, ["shield", *DOCS_SHIELD, *extra, "--emit", "python",
                                    "--emit", "gwendolen", "-o", str(folder)])
    assert got.exit_code == 0, got.output
    return folder


@pytest.fixture(scope="module")
def docs_forms(tmp_path_factory) -> Path:
    return write_docs_forms(tmp_path_factory.mktemp("gwendolen"))


@pytest.mark.tor("TOR-SHD-006")
def test_the_agent_decides_each_tick_with_the_shields_machine(docs_forms):
    gwen = (docs_forms / "safe_ros.gwen").read_text(encoding="utf-8")
    assert ":name: agilex_agent" in gwen
    plan = ("+tick(Tick) : {B mem(State, Was, Broken)} <- shield(State, Out, Next, Now), "
            "-mem(State, Was, Broken), +mem(Next, Out, Now), publish(Out);")
    assert plan in gwen.splitlines()
    # the outputs are read off the machine's decision, not set by plans of their own
    assert "stopped :- mem(_, v(1,_,_,_,_,_,_,_), _);" in gwen.splitlines()
    assert "R5: monitored only, not in the agent" in gwen
    java = (docs_forms / "safe_ros_shield.java").read_text(encoding="utf-8")
    assert 'INPUT_ATOMS = {"too_close", "scan_stale", "obstacle_ahead", "obstacle_behind"}' \
        in java


def _psl(folder: Path) -> dict[str, str]:
    """label -> formula of the ``.psl`` (AJPF's reader: ``#`` lines are comments)."""
    out = {}
    for line in (folder / "safe_ros.psl").read_text(encoding="utf-8").splitlines():
        if line and not line.startswith("#"):
            label, formula = line.split(":", 1)
            out[label] = formula.strip()
    return out


def test_the_properties_state_immediately_exactly_and_say_what_they_leave_out(docs_forms):
    props = _psl(docs_forms)
    assert list(props) == ["R2", "R3", "R4", "R6", "R8", "R9", "R10", "R11",
                           "release_stopped", "release_stop_requested",
                           "release_forwarded_zero"]
    # immediately: at the tick of the condition, no <> (it was read as eventually before)
    assert props["R3"] == ("[] ((B(agilex_agent,decided) & B(agilex_agent,stop_requested)) -> "
                           "B(agilex_agent,forwarded_zero))")
    assert "<>" not in props["R8"] and "<>" not in props["R9"]
    text = (docs_forms / "safe_ros.psl").read_text(encoding="utf-8")
    assert ("# R2: upon too_close agilex_agent shall within 1 second satisfy stopped\n"
            "#   the response eventually; its deadline of 10 tick(s) is not stated: AJPF's "
            "LTL cannot count ticks") in text
    assert "that it holds for 10 tick(s) is not stated" in text  # R11's 'for 1 second'
    assert "# R5: monitored only" in text
    assert props["release_stopped"].endswith("-> (<> ([] ~B(agilex_agent,stopped))))")


#: the numbers the proposals take: each side of every output comparison's constant
_SPEEDS = [0.0, 0.1, 0.15, 0.2, 0.5, 0.7]
_VELOCITIES = [-0.3, -0.1, 0.0, 0.1, 0.3]
#: the clearances (m): each side of environment.fret's 0.05 and 0 (an assumption broken)
_CLEARANCES = [1.0, 1.0, 0.2, 0.04, 0.0]


def _random_runs(seed: int, runs: int, ticks: int) -> list[list[tuple[dict, dict]]]:
    """``runs`` runs of ``ticks`` ticks: each input held from the tick before with
    probability 0.8 (so obstacles stay and go, and stops are held and released), proposals
    drawn afresh each tick, half of them the controller pushing on (nothing stopped, full
    speed)."""
    rng = random.Random(seed)
    out = []
    for _ in range(runs):
        ins = {"too_close": False, "scan_stale": False, "obstacle_ahead": False,
               "obstacle_behind": False}
        run = []
        for _t in range(ticks):
            ins = {k: (v if rng.random() < 0.8 else not v) for k, v in ins.items()}
            if rng.random() < 0.5:
                prop = {"stopped": False, "stop_requested": False, "forwarded_zero": False,
                        "linear_speed": 0.7, "angular_speed": 0.7, "linear_velocity": 0.3}
            else:
                prop = {"stopped": rng.random() < 0.3, "stop_requested": rng.random() < 0.3,
                        "forwarded_zero": rng.random() < 0.3,
                        "linear_speed": rng.choice(_SPEEDS),
                        "angular_speed": rng.choice(_SPEEDS),
                        "linear_velocity": rng.choice(_VELOCITIES)}
            run.append(({**ins, "clearance": rng.choice(_CLEARANCES)}, prop))
        out.append(run)
    return out


def java_steps(folder: Path, lines: list[str], tmp: Path) -> list[str]:
    """``N_shield.java``'s ``main`` over ``lines`` ("INPUTS PROPOSAL STATE"), compiled with
    javac and run with the ``java`` beside it."""
    javac = shutil.which("javac")
    if javac is None:
        pytest.skip(NO_JAVAC)
    classes = tmp / "classes"
    subprocess.run([javac, "-nowarn", "-d", str(classes), str(folder / "safe_ros_shield.java")],
                   check=True, capture_output=True, timeout=300)
    java = Path(javac).with_name("java")
    got = subprocess.run([str(java), "-cp", str(classes), "safe_ros_shield"],
                         input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True, timeout=300)
    return got.stdout.splitlines()


def python_steps(folder: Path, runs: list[list[tuple[dict, dict]]]
                 ) -> tuple[list[str], list[str]]:
    """The Python form (``safe_ros_shield.py``) stepped over ``runs``: per tick the line
    ``N_shield.java`` reads (the input and proposed atoms, the state before) and the line it
    must print (the decided atoms, the next state, whether an assumption broke)."""
    shield = load_shield((folder / "safe_ros_shield.py").read_text(encoding="utf-8"),
                         "gwendolen_diff_shield")()
    return machine_lines(shield, runs)


@pytest.mark.tor("TOR-SHD-006")
def test_the_java_machine_holds_and_releases_the_stop_as_the_python_form(docs_forms, tmp_path):
    """Differential: 200 seeded random runs of 60 ticks through both forms, every tick's
    decided output atoms, next state and broken flag equal. The runs hold stops and release
    them (checked below), so a machine that latched the stop, or released it early, differs."""
    runs = _random_runs(seed=83, runs=200, ticks=60)
    lines, want = python_steps(docs_forms, runs)
    got = java_steps(docs_forms, lines, tmp_path)
    assert len(got) == len(want)
    diff = [(k, lines[k], want[k], got[k]) for k in range(len(want)) if got[k] != want[k]]
    assert not diff, diff[:5]
    # the runs exercise what the agent must get right: stopped held, then released
    stopped = [int(w[0]) for w in want]
    releases = sum(1 for a, b in zip(stopped, stopped[1:]) if a == 1 and b == 0)
    assert releases > 50 and sum(stopped) > 500


def test_a_latching_machine_is_caught_by_the_differential(docs_forms, tmp_path):
    """The comparison can fail: a Java machine whose ``stopped`` stays true once set (the
    agent the issue found) differs from the Python form on these runs."""
    java = (docs_forms / "safe_ros_shield.java").read_text(encoding="utf-8")
    latch = java.replace("        return new int[][] {out, next, {broken ? 1 : 0}};",
                         "        LATCH = LATCH || out[0] == 1;\n        out[0] = LATCH ? 1 : "
                         "out[0];\n        return new int[][] {out, next, {broken ? 1 : 0}};")
    latch = latch.replace("    private safe_ros_shield() {", "    static boolean LATCH = false;\n"
                          "\n    private safe_ros_shield() {")
    assert latch != java
    folder = tmp_path / "latch"
    folder.mkdir()
    (folder / "safe_ros_shield.java").write_text(latch, encoding="utf-8")
    (folder / "safe_ros_shield.py").write_text(
        (docs_forms / "safe_ros_shield.py").read_text(encoding="utf-8"), encoding="utf-8")
    lines, want = python_steps(folder, _random_runs(seed=83, runs=20, ticks=60))
    got = java_steps(folder, lines, tmp_path)
    assert got != want


def test_under_assumptions_the_broken_flag_and_the_fallback_match(tmp_path):
    """With ``--assume requirements/shield/environment.fret``, the ticks at which an
    assumption of the environment is broken give the fallback in both forms, flagged."""
    folder = write_docs_forms(tmp_path / "assume", "--assume",
                              str(REQS / "shield" / "environment.fret"))
    runs = _random_runs(seed=7, runs=60, ticks=40)
    lines, want = python_steps(folder, runs)
    got = java_steps(folder, lines, tmp_path)
    assert got == want
    assert any(w.endswith(" 1") for w in want) and any(w.endswith(" 0") for w in want)


@pytest.mark.tor("TOR-SHD-006")
def test_the_environment_lists_the_valuations_real_numbers_give(docs_forms):
    env = (docs_forms / "safe_ros_env.java").read_text(encoding="utf-8")
    m = re.search(r"static final int\[\] VALUATIONS = \{([^}]*)\};", env)
    assert m is not None
    assert [int(x) for x in m.group(1).split(",")] == list(range(16))  # four free booleans
    assert "//   push: 00000001 " in env and "//   stop: 11111111 " in env


@pytest.mark.tor("TOR-SHD-006")
def test_a_shield_with_preferences_decides_alike_in_java(tmp_path):
    """A shield with ``--prefer`` (its corrections weighed): the Java machine carries the
    weights and decides as the Python form on the qualify check's seeded runs."""
    from fretc.qualification.checks_shield import _java_runs

    javac = shutil.which("javac")
    if javac is None:
        pytest.skip(NO_JAVAC)
    (tmp_path / "s.fret").write_text("S1: whenever x > 5 ctrl shall immediately satisfy o\n"
                                     "S2: upon x > 5 ctrl shall for 2 ticks satisfy o\n")
    (tmp_path / "s.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                                     'x = "/x.data"\no = "/o.data"\n')
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "s.fret"), "-b",
                                    str(tmp_path / "s.toml"), "--inputs", "x", "--outputs", "o",
                                    "--prefer", "!o", "--emit", "python", "--emit", "gwendolen",
                                    "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output
    java_text = (tmp_path / "out" / "s_shield.java").read_text(encoding="utf-8")
    assert "new long[] {1}" in java_text  # (the weight of the preferred literal)
    shield = load_shield((tmp_path / "out" / "s_shield.py").read_text(encoding="utf-8"),
                         "gwendolen_prefer_shield")()
    lines, want = machine_lines(shield, _java_runs())
    classes = tmp_path / "classes"
    subprocess.run([javac, "-nowarn", "-d", str(classes), str(tmp_path / "out" / "s_shield.java")],
                   check=True, capture_output=True, timeout=300)
    ran = subprocess.run([str(Path(javac).with_name("java")), "-cp", str(classes), "s_shield"],
                         input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True, timeout=300)
    assert ran.stdout.splitlines() == want


@pytest.mark.tor("TOR-SHD-006")
def test_atoms_whose_texts_give_one_term_get_terms_of_their_own():
    """Four atoms whose texts give the one Gwendolen term ``a_b`` (and an output beside
    them): each gets a term of its own, numbered in order, none an agent's own name."""
    from types import SimpleNamespace

    from fretc.shield.emit_gwendolen import AgentAtoms

    def atoms(*texts: str) -> list:
        return [SimpleNamespace(text=t) for t in texts]

    three = SimpleNamespace(machines=[SimpleNamespace(inputs=atoms("a.b", "a,b", "a;b"),
                                                      outputs=[])])
    got = AgentAtoms(three).term  # type: ignore[arg-type]
    assert got == {"a.b": "a_b", "a,b": "a_b_2", "a;b": "a_b_3"}, got
    shield = SimpleNamespace(machines=[SimpleNamespace(inputs=atoms("a.b", "a,b", "a;b"),
                                                       outputs=atoms("a:b", "tick"))])
    got = AgentAtoms(shield).term  # type: ignore[arg-type]
    assert got == {"a.b": "a_b", "a,b": "a_b_2", "a;b": "a_b_3", "a:b": "a_b_4",
                   "tick": "tick_2"}, got


@pytest.mark.tor("TOR-SHD-006")
@pytest.mark.parametrize("then,fallback,want", [
    # atoms v > 1, v > 2 (one message cannot give 01), the fallback 10: the opposite, 01,
    # is no message; 00 and 11 are each one atom from it, and 00 comes first
    ("v > 1 & !(v > 2)", "v=1.5", "{{0, 0}, {1, 0}}"),
    # the fallback's atoms below the push proposal's: both proposed
    ("!(v > 1)", "v=0", "{{1}, {0}}")])
def test_the_controllers_proposals_are_the_nearest_opposite_of_the_fallback_and_the_fallback(
        tmp_path, then, fallback, want):
    """The environment's proposals (``push``: the message nearest every output atom the
    opposite of the fallback's, ties to the first in binary order; ``stop``: the fallback's)
    for a fallback whose opposite no message gives, and for one below the push proposal."""
    (tmp_path / "s.fret").write_text(f"S1: whenever x > 5 ctrl shall immediately satisfy {then}\n")
    (tmp_path / "s.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                                     'x = "/x.data"\nv = "/v.data"\n')
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "s.fret"), "-b",
                                    str(tmp_path / "s.toml"), "--inputs", "x", "--outputs", "v",
                                    "--fallback", fallback, "--emit", "gwendolen",
                                    "-o", str(tmp_path / "out")])
    assert got.exit_code == 0, got.output
    env = (tmp_path / "out" / "s_env.java").read_text(encoding="utf-8")
    assert 'PROPOSAL_NAMES = {"push", "stop"};' in env
    assert f"PROPOSALS = {want};" in env, re.findall(r"PROPOSALS = .*", env)
