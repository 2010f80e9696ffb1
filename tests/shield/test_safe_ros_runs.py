"""The Safe-ROS shield (Python and C forms) driven by random inputs and random proposals for
thousands of ticks (hypothesis draws the runs): ``fretc audit`` of each corrected trace, as a
CSV of FRET variables, finds no enforced requirement violated, and at every tick whose
proposal was safe the output is the proposal."""

from __future__ import annotations

import csv
import random
import subprocess
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_python import tables
from fretc.shield.runtime import ShieldRuntime
from fretc.signals.bindings.files import load_bindings

from _c_monitors import build, c_compiler, write
from _gen import atoms_of, safe

REPO = Path(__file__).resolve().parents[2]
REQS = REPO / "requirements" / "safe_ros.fret"
INPUTS = ["too_close", "scan_stale", "clearance"]
OUTPUTS = ["stopped", "stop_requested", "forwarded_zero", "linear_speed", "angular_speed"]
_SHIELD: list = []


def _shield():
    if not _SHIELD:
        compiled = compile_entries(load_requirements([REQS]))
        _SHIELD.append(build_shield(compiled, INPUTS, OUTPUTS, bindings=load_bindings(
            REPO / "requirements" / "safe_ros.bindings.toml"), fork=False, name="safe_ros"))
    return _SHIELD[0]


def _run(seed: int, n: int) -> list[tuple[dict, dict]]:
    rnd = random.Random(seed)
    out, close, stale = [], False, False
    for _ in range(n):
        close = close if rnd.random() < 0.85 else not close
        stale = stale if rnd.random() < 0.95 else not stale
        out.append(({"too_close": close, "scan_stale": stale,
                     "clearance": rnd.choice([-0.1, 0.5, 2.0])},
                    {"stopped": rnd.random() < 0.2, "stop_requested": rnd.random() < 0.1,
                     "forwarded_zero": rnd.random() < 0.1,
                     "linear_speed": rnd.choice([0.0, 0.0005, 0.3, 0.5, 0.7]),
                     "angular_speed": rnd.choice([0.0, 0.2, 0.6])}))
    return out


def _audit(rows: list[dict], folder: Path) -> dict[str, str]:
    path = folder / "corrected.csv"
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=INPUTS + OUTPUTS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (str(v).lower() if isinstance(v, bool) else repr(float(v)))
                        for k, v in r.items()})
    req = folder / "safe_ros.fret"  # alone: the bindings beside the original are the robot's
    req.write_text(REQS.read_text(encoding="utf-8"), encoding="utf-8")
    plan = load_plan(AuditConfig(requirements=[str(req)]))
    return {v.requirement: v.verdict for v in audit_log(plan, str(path)).verdicts}


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), n=st.integers(1000, 3000))
def test_the_python_shield_keeps_r2_r3_r4_r6_on_thousands_of_ticks(seed, n):
    shield = _shield()
    (m,) = shield.machines
    rt = ShieldRuntime(tables(shield))
    rows, raw = [], []
    for ins, prop in _run(seed, n):
        raw.append({**ins, **prop})
        before = rt.machines[0].state
        d = rt.step(ins, prop)
        if safe(m, before, ins, atoms_of(m, prop)):
            assert not d.overridden and d.outputs == prop
        rows.append({**ins, **d.outputs})
    with tempfile.TemporaryDirectory() as tmp:
        got = _audit(rows, Path(tmp))
        unshielded = _audit(raw, Path(tmp))
    for rid in ("R2", "R3", "R4", "R6"):
        assert got[rid] in ("satisfied", "vacuous"), (rid, got)
    assert unshielded["R4"] == "violated"  # the proposals alone break the speed limits


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31))
def test_the_c_shield_keeps_them_too(seed):
    if c_compiler() is None:
        return  # tests/shield/test_c.py skips, naming why
    shield = _shield()
    run = _run(seed, 2000)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render_c(shield, "s"), folder)
        exe = build(folder, ["s_shield.c", "s_shield_run.c"], "run")
        lines = [",".join(INPUTS + OUTPUTS)]
        for ins, prop in run:
            lines.append(",".join([str(ins[v]).lower() if isinstance(ins[v], bool)
                                   else repr(ins[v]) for v in INPUTS]
                                  + [str(prop[v]).lower() if isinstance(prop[v], bool)
                                     else repr(prop[v]) for v in OUTPUTS]))
        got = subprocess.run([str(exe)], input="\n".join(lines) + "\n", capture_output=True,
                             text=True, timeout=60, check=True)
        out = list(csv.DictReader(got.stdout.splitlines()))
        rows = []
        for (ins, _prop), r in zip(run, out, strict=True):
            rows.append({**ins, **{v: (r[v] == "1") if v not in shield.numbers
                                   else float(r[v]) for v in OUTPUTS}})
        verdicts = _audit(rows, folder)
    for rid in ("R2", "R3", "R4", "R6"):
        assert verdicts[rid] in ("satisfied", "vacuous"), (rid, verdicts)
