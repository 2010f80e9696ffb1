"""``fretc shield`` measured: synthesis time, one step of the Python and C shields against the
generated monitors of the same requirements (the baseline: a shield is a monitor that also
corrects), and a shield for every FRET case-study set that ``fretc check`` decides realizable.

    python bench/bench_shield.py [--steps 2000000] [--corpus ../shared/corpora/fret_casestudies.jsonl]

1. Synthesis of the Safe-ROS set (R2..R6 with their bindings): CPU of the command a user runs
   (``fretc shield ... --emit python``, start-up included) and of the synthesis in process.
2. One step on a random run (inputs and proposals drawn once, the same for every engine):
   the Python shield's ``step`` against the generated Python monitors' ``step`` of the same
   requirements (per tick, all requirements), and the C shield's ``P_shield_step`` against
   the C monitors' steps (``cc -O2``, arrays in memory, ``clock_gettime``). Ratios in one run.
3. The case studies: per FRET project of the corpus, outputs = the variables its responses
   read, inputs = the rest; ``fretc check``'s realizability per component with its default
   budgets; for each realizable set, the shield within the same budgets (synthesized or not),
   with the CPU of each (in process; the shield's games in ``check``'s worker process, whose
   CPU counts as the children's).
"""

from __future__ import annotations

import argparse
import random
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from _c_monitors import c_compiler, write  # noqa: E402

from fretc.compiler.build import compile_entries  # noqa: E402
from fretc.fretish.files import load_requirements  # noqa: E402
from fretc.shield.build import build_shield  # noqa: E402
from fretc.shield.emit_c import render_c  # noqa: E402
from fretc.shield.emit_python import load_shield, render_python  # noqa: E402
from fretc.signals.bindings.files import load_bindings  # noqa: E402

REQS = ROOT / "requirements"
INPUTS = ["too_close", "scan_stale", "clearance"]
OUTPUTS = ["stopped", "stop_requested", "forwarded_zero", "linear_speed", "angular_speed"]


def cpu() -> float:
    s = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def synthesis() -> object:
    """Part 1; returns the Safe-ROS shield and its requirements."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = cpu()
        subprocess.run([sys.executable, "-m", "fretc", "shield", str(REQS / "safe_ros.fret"),
                        "-b", str(REQS / "safe_ros.bindings.toml"), "--inputs",
                        ",".join(INPUTS), "--outputs", ",".join(OUTPUTS), "--emit", "python",
                        "-o", tmp], check=True, capture_output=True)
        command = cpu() - t0
    compiled = compile_entries(load_requirements([REQS / "safe_ros.fret"]))
    bindings = load_bindings(REQS / "safe_ros.bindings.toml")
    t0 = cpu()
    shield = build_shield(compiled, INPUTS, OUTPUTS, bindings=bindings, fork=False,
                          name="safe_ros")
    inproc = cpu() - t0
    print(f"1. synthesis of the Safe-ROS shield: {command:.2f} s CPU as the command "
          f"(start-up included), {inproc:.3f} s in process")
    return shield, compiled


def _run(n: int, seed: int = 1, hostile: bool = True) -> list[tuple[dict, dict]]:
    """``n`` ticks: inputs in runs of a few ticks; proposals over the speed limits half of
    the time (``hostile``), or always within them (most ticks kept)."""
    rnd = random.Random(seed)
    lins = [0.0, 0.3, 0.45, 0.6] if hostile else [0.0, 0.3, 0.45]
    angs = [0.0, 0.2, 0.7] if hostile else [0.0, 0.2]
    out = []
    close = stale = False
    for _ in range(n):
        close = (rnd.random() < 0.9) == close  # runs of ten ticks on average
        stale = (rnd.random() < 0.97) == stale
        out.append(({"too_close": close, "scan_stale": stale, "clearance": 1.0},
                    {"stopped": rnd.random() < 0.1, "stop_requested": False,
                     "forwarded_zero": False, "linear_speed": rnd.choice(lins),
                     "angular_speed": rnd.choice(angs)}))
    return out


def _time_shield(sh, run, steps: int) -> tuple[float, int]:
    t0 = time.perf_counter()
    k = overridden = 0
    while k < steps:
        for ins, prop in run:
            overridden += sh.step(ins, prop).overridden
        k += len(run)
    return (time.perf_counter() - t0) / k * 1e6, overridden


def python_step(shield, compiled, steps: int) -> None:
    """Part 2, Python: the shield on a run whose proposals are mostly kept, and on one whose
    proposals break the speed limits half of the time, against the monitors."""
    from fretc.compiler.codegen import build_monitor_module

    cls = load_shield(render_python(shield))
    figures = {}
    for hostile in (False, True):
        run = _run(min(steps, 200_000), hostile=hostile)
        figures[hostile] = _time_shield(cls(), run, steps)
    mm = build_monitor_module([c for c in compiled if c.id != "R5"], "bench_shield_monitors")
    mod = type(sys)("bench_shield_monitors")
    exec(compile(mm.text, "bench_shield_monitors", "exec"), mod.__dict__)
    monitors = [m() for m in mod.MONITORS.values()]
    samples = [{**ins, **prop} for ins, prop in _run(min(steps, 200_000), hostile=False)]
    t0 = time.perf_counter()
    k = 0
    while k < steps:
        for s in samples:
            for m in monitors:
                m.step(s)
        k += len(samples)
    mon_us = (time.perf_counter() - t0) / k * 1e6
    for hostile, (us, over) in figures.items():
        kind = "proposals over the limits half of the time" if hostile else "proposals kept"
        print(f"2a. Python ({kind}; {100 * over / steps:.1f} % of ticks overridden): shield "
              f"step {us:.2f} us; the monitors of R2, R3, R4, R6 {mon_us:.2f} us a tick: "
              f"ratio {us / mon_us:.2f}")


_DRIVER = """
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "b_shield.h"
static const unsigned char close_[N] = {CLOSE};
static const unsigned char stale_[N] = {STALE};
static const double lin_[N] = {LIN};
static const double ang_[N] = {ANG};
static const unsigned char stopped_[N] = {STOPPED};
int main(void) {
    b_shield_state s; b_shield_inputs in = {0}; b_shield_outputs p = {0}, c;
    struct timespec a, b; long k, steps = STEPS, sum = 0, first = 0; int r;
    double best = 1e30, ns;
    for (r = 0; r < 5; r++) { /* the best of 5 runs of the same steps from the initial state */
        b_shield_init(&s);
        sum = 0;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (k = 0; k < steps; k++) {
            int i = (int)(k % NTICKS);
            in.too_close = close_[i]; in.scan_stale = stale_[i];
            p.stopped = stopped_[i]; p.linear_speed = lin_[i]; p.angular_speed = ang_[i];
            sum += b_shield_step(&s, &in, &p, &c);
        }
        clock_gettime(CLOCK_MONOTONIC, &b);
        ns = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / steps;
        best = ns < best ? ns : best;
        if (r == 0) first = sum;
        if (sum != first) return 1;
    }
    printf("%.2f %ld\\n", best, sum);
    return 0;
}
"""


def _c_shield_ns(cc: str, shield, run, steps: int) -> tuple[float, int]:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(render_c(shield, "b"), folder)
        arr = lambda xs: ", ".join(str(x) for x in xs)  # noqa: E731
        src = (_DRIVER.replace("N]", f"{len(run)}]").replace("NTICKS", str(len(run)))
               .replace("STEPS", str(steps))
               .replace("{CLOSE}", "{" + arr(int(i["too_close"]) for i, _p in run) + "}")
               .replace("{STALE}", "{" + arr(int(i["scan_stale"]) for i, _p in run) + "}")
               .replace("{LIN}", "{" + arr(p["linear_speed"] for _i, p in run) + "}")
               .replace("{ANG}", "{" + arr(p["angular_speed"] for _i, p in run) + "}")
               .replace("{STOPPED}", "{" + arr(int(p["stopped"]) for _i, p in run) + "}"))
        (folder / "drive.c").write_text(src)
        subprocess.run([cc, "-std=c99", "-O2", "-o", "drive", "b_shield.c", "drive.c", "-lm"],
                       cwd=folder, check=True)
        ns, overrides = subprocess.run(["./drive"], cwd=folder, capture_output=True,
                                       text=True, check=True).stdout.split()
    return float(ns), int(overrides)


def _c_monitors_ns(cc: str, compiled, run, steps: int) -> float:
    """The C monitors of R2, R3, R4, R6 (``--emit c``) on the same run: ns a tick, all four."""
    from bench_c_monitors import driver

    from fretc.compiler.c_codegen import c_units, emit_c

    group = [c for c in compiled if c.id != "R5"]
    trace = [{**i, **p} for i, p in run]
    files, _skipped = emit_c(group)
    units = c_units(group)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(files, folder)
        (folder / "bench.c").write_text(driver(units, trace, steps))
        subprocess.run([cc, "-std=c99", "-O2", "-o", "bench",
                        *[u.stem + ".c" for u in units], "bench.c", "-lm"], cwd=folder,
                       check=True)
        out = subprocess.run(["./bench"], cwd=folder, capture_output=True, text=True,
                             check=True).stdout
    return sum(float(line.split()[1]) for line in out.splitlines())


def c_step(shield, compiled, steps: int) -> None:
    """Part 2, C: the shield's step and the C monitors' steps of the same requirements on
    the same runs (``cc -O2``, arrays in memory)."""
    cc = c_compiler()
    if cc is None:
        print("2b. C: no C compiler")
        return
    for hostile in (False, True):
        run = _run(10_000, hostile=hostile)
        ns, over = _c_shield_ns(cc, shield, run, steps)
        mon = _c_monitors_ns(cc, compiled, run, steps)
        kind = "proposals over the limits half of the time" if hostile else "proposals kept"
        print(f"2b. C ({kind}; {100 * over / steps:.1f} % overridden): shield step {ns:.1f} ns; "
              f"the C monitors of R2, R3, R4, R6 {mon:.1f} ns a tick: ratio {ns / mon:.2f}")


def case_studies(corpus: Path) -> None:
    """Part 3."""
    from bench_check import corpus_groups
    from fretc.check.analysis import check_requirements
    from fretc.compiler.build import compile_entry
    from fretc.shield.build import ShieldUnknown
    from fretc.shield.plan import ShieldError

    decided = made = refused = unknown = 0
    t0 = cpu()
    for group, entries in corpus_groups(corpus).items():
        compiled = [c for c in (compile_entry(e) for e in entries) if c.formalization]
        if not compiled:
            continue
        outs = sorted(_response_vars(compiled))
        ins = sorted({v for c in compiled for v in c.formalization.variables} - set(outs))
        t1 = cpu()
        res = check_requirements(compiled, inputs=ins, outputs=outs, redundancy=False,
                                 vacuity=False)
        t_check = cpu() - t1
        rz = res.realizability or {"groups": []}
        if not rz["groups"] or not all(c["realizable"] is True for c in rz["groups"]):
            continue
        decided += 1
        t1 = cpu()
        try:
            shield = build_shield(compiled, ins, outs, name=group.replace("/", "_"))
            made += 1
            preds = sum(a.op == "pred" for m in shield.machines for a in m.outputs)
            print(f"   {group}: shield in {cpu() - t1:.2f} s CPU (check {t_check:.2f} s); "
                  f"{len(shield.machines)} machines, {preds} comparisons of several variables")
        except ShieldUnknown as exc:
            unknown += 1
            print(f"   {group}: unknown: {str(exc).splitlines()[0][:160]}")
        except ShieldError as exc:
            refused += 1
            print(f"   {group}: refused after {cpu() - t1:.2f} s CPU (check {t_check:.2f} s): "
                  f"{str(exc).splitlines()[0][:200]}")
    print(f"3. case studies: {decided} sets decided realizable by fretc check; shields "
          f"synthesized for {made}, refused {refused} (not enforceable: see above), unknown "
          f"{unknown}; {cpu() - t0:.1f} s CPU in all")


def _response_vars(compiled) -> set[str]:
    from fretc.compiler.expressions import Expander
    from fretc.compiler import ir

    ex = Expander("pt", ir.TRUE, ir.TRUE)
    out: set[str] = set()
    for c in compiled:
        try:
            out.update(ir.variables(ex.bool(c.entry.requirement.response)))
        except Exception:  # noqa: BLE001 - a response the expander refuses has no outputs
            pass
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2_000_000)
    ap.add_argument("--corpus", type=Path,
                    default=ROOT.parent / "shared" / "corpora" / "fret_casestudies.jsonl")
    ap.add_argument("--skip-corpus", action="store_true")
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT / "bench"))
    shield, compiled = synthesis()
    python_step(shield, compiled, min(args.steps, 400_000))
    c_step(shield, compiled, args.steps)
    if not args.skip_corpus and args.corpus.exists():
        case_studies(args.corpus)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
