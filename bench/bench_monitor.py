"""Per-tick cost of generated monitors against reelay (PyPI ``reelay``, a C++ runtime
verification library with Python bindings) on the same past-time formula and trace.

    python bench/bench_monitor.py [--ticks 200000] [--baseline DIR]

Monitors: Safe-ROS R1 and ``in m upon p the sw shall within 10 ticks satisfy q``. For each,
our generated monitor's ``step()`` (pt verdict + LTL3 status), its ``run()`` (the same over
the whole trace in one call; asserted equal to ``step()``) and reelay's
``discrete_timed_monitor`` on the same pt formula (translated to reelay's Rye syntax) run over
the same random trace in one process. Prints microseconds per step and the ratio.
Both monitors' verdicts are compared tick by tick where their semantics coincide.

``--baseline DIR`` also steps the monitors another checkout of fretc generates (e.g.
``git archive main | tar -x -C DIR``; its module is rendered in a child process and loaded
here, generated modules being standalone) over the same trace, alternating with ours over
``--rounds`` rounds (best round of each), and prints the ratio and whether the verdicts and
LTL3 statuses are equal tick by tick.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import time
import types
from types import SimpleNamespace

from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import render_module
from fretc.compiler.ir import Node
from fretc.fretish import parse

REQUIREMENTS = {
    "R1": "whenever too_close agilex_agent shall eventually satisfy stopped",
    "R2": "in m upon p the sw shall within 10 ticks satisfy q",
}


def to_rye(n: Node, witness: str) -> str:
    """Reelay Rye text of a pt formula (atoms ``{name}``, ``pre``, ``since``, ``once[a:b]``,
    ``historically[a:b]``), every operation parenthesized. Rye has no constants: TRUE is
    written ``({w} or (not {w}))`` with ``witness`` a variable of the trace."""
    op = n.op
    a = n.args

    # same shape as compiler.ajpf's go: a case per IR operator (kept: Rye spells every case its own
    # way)
    def go(x: Node) -> str:
        return to_rye(x, witness)

    true = f"({{{witness}}} or (not {{{witness}}}))"
    if op == "ap":
        return "{" + n.name + "}"
    if op == "true":
        return true
    if op == "false":
        return f"(not {true})"
    if op == "FTP":
        return f"(not (pre {true}))"
    # the operator cases below are alike but for Rye's words (kept: one case per operator)
    if op == "!":
        return f"(not {go(a[0])})"
    if op == "&":
        return f"({go(a[0])} and {go(a[1])})"
    if op == "|":
        return f"({go(a[0])} or {go(a[1])})"
    if op == "->":
        return f"({go(a[0])} implies {go(a[1])})"
    if op == "Y":
        return f"(pre {go(a[0])})"
    if op == "Z":
        return f"((not (pre {true})) or (pre {go(a[0])}))"
    if op in ("O", "H"):
        word = "once" if op == "O" else "historically"
        bound = "" if n.hi is None else f"[{n.lo}:{n.hi}]"
        return f"({word}{bound} {go(a[0])})"
    if op == "S":
        return f"({go(a[0])} since {go(a[1])})"
    raise ValueError(f"no Rye form for {op}")


# Renders the module of REQUIREMENTS with the fretc on PYTHONPATH (the baseline); prints it.
RENDER = r"""
import json, sys
from types import SimpleNamespace
from fretc.compiler.build import compile_entry
from fretc.compiler.codegen import render_module
from fretc.fretish import parse
entries = [SimpleNamespace(id=rid, text=text, source="bench.fret", line=1, column=1,
                           rationale=None, parent=None, tick_period=None,
                           requirement=parse(text), error=None, extra={})
           for rid, text in json.loads(sys.argv[1]).items()]
sys.stdout.write(render_module([compile_entry(e) for e in entries], "bench_monitors"))
"""


def load_text(text: str, name: str) -> types.ModuleType:
    mod = types.ModuleType(name)
    exec(compile(text, name, "exec"), mod.__dict__)
    return mod


def run(cls, trace) -> tuple[float, list, list]:
    """(CPU seconds, verdicts, statuses) of one monitor of ``cls`` over ``trace``."""
    m = cls()
    step = m.step
    t0 = time.process_time()
    verdicts = [step(s) for s in trace]
    t = time.process_time() - t0
    m.reset()
    statuses = []
    for s in trace:
        m.step(s)
        statuses.append(m.status)
    return t, verdicts, statuses


BOUNDS = (10, 10_000)


def bound_cost(mod_for, ticks: int) -> None:
    """Per-step cost of ``upon p the sw shall within N ticks satisfy q`` and of ``after N
    ticks`` at N = 10 and 10,000 (pt has ``O[N,N]``, ``O[0,N-1]``): the cost must not grow
    with the bound (aim: 10,000 within 1.5x of 10)."""
    rnd = random.Random(7)
    trace = [{"p": rnd.random() < 0.05, "q": rnd.random() < 0.3} for _ in range(ticks)]
    for timing in ("within", "after"):
        costs = []
        for n in BOUNDS:
            text = f"upon p the sw shall {timing} {n} ticks satisfy q"
            e = SimpleNamespace(id=f"B{n}", text=text, source="bench.fret", line=1, column=1,
                                rationale=None, parent=None, tick_period=None,
                                requirement=parse(text), error=None, extra={})
            c = compile_entry(e)
            mod = mod_for([c])
            best = min(run(mod.MONITORS[c.id], trace)[0] for _ in range(3))
            costs.append(1e6 * best / ticks)
        print(f"bound cost, `upon p ... {timing} N ticks`: N={BOUNDS[0]} {costs[0]:.3f} µs/step, "
              f"N={BOUNDS[1]} {costs[1]:.3f} µs/step, ratio {costs[1] / costs[0]:.2f}x "
              "(aim <= 1.5x)")


def compare_baseline(compiled, mod, baseline: str, ticks: int, rounds: int) -> None:
    env = dict(os.environ, PYTHONPATH=baseline)
    text = subprocess.run([sys.executable, "-c", RENDER, json.dumps(REQUIREMENTS)], env=env,
                          cwd=baseline, check=True, stdout=subprocess.PIPE).stdout.decode()
    base = load_text(text, "baseline_monitors")
    rnd = random.Random(7)
    print(f"\nagainst the baseline {baseline} ({rounds} alternating rounds, best of each, "
          "CPU time)")
    print(f"{'monitor':<6} {'fretc µs/step':>14} {'baseline µs/step':>17} "
          f"{'baseline/fretc':>15}  verdicts and statuses equal")
    for c in compiled:
        names = c.formalization.variables
        trace = [{v: rnd.random() < (0.9 if v == "m" else 0.3) for v in names}
                 for _ in range(ticks)]
        best = {"fretc": float("inf"), "baseline": float("inf")}
        outputs = {}
        for _ in range(rounds):
            for label, m in (("fretc", mod), ("baseline", base)):
                t, verdicts, statuses = run(m.MONITORS[c.id], trace)
                best[label] = min(best[label], t)
                outputs[label] = (verdicts, statuses)
        us = {k: 1e6 * v / ticks for k, v in best.items()}
        print(f"{c.id:<6} {us['fretc']:>14.3f} {us['baseline']:>17.3f} "
              f"{us['baseline'] / us['fretc']:>14.2f}x  "
              f"{outputs['fretc'] == outputs['baseline']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=200_000)
    ap.add_argument("--baseline", default=None)
    ap.add_argument("--rounds", type=int, default=9)
    args = ap.parse_args()
    import reelay

    entries = [SimpleNamespace(id=rid, text=text, source="bench.fret", line=1, column=1,
                               rationale=None, parent=None, tick_period=None,
                               requirement=parse(text), error=None, extra={})
               for rid, text in REQUIREMENTS.items()]
    compiled = [compile_entry(e) for e in entries]
    mod = load_text(render_module(compiled, "bench_monitors"), "bench_monitors")
    rnd = random.Random(5)
    print(f"ticks per run: {args.ticks}")
    print(f"{'monitor':<6} {'fretc µs/step':>14} {'reelay µs/step':>15} {'reelay/fretc':>13}"
          f"  verdicts equal")
    for c in compiled:
        names = c.formalization.variables
        # sparse triggers so that obligations are both met and missed
        trace = [{v: rnd.random() < (0.9 if v == "m" else 0.3) for v in names}
                 for _ in range(args.ticks)]
        m = mod.MONITORS[c.id]()
        step = m.step
        t0 = time.perf_counter()
        ours = [step(s) for s in trace]
        t_ours = time.perf_counter() - t0

        m2 = mod.MONITORS[c.id]()
        t0 = time.perf_counter()
        ours_run = m2.run(trace)
        t_run = time.perf_counter() - t0
        assert ours_run == ours and m2.status == m.status, "run() differs from step()"

        rm = reelay.discrete_timed_monitor(pattern=to_rye(c.formalization.pt, names[0]), condense=False)
        upd = rm.update
        t0 = time.perf_counter()
        theirs = [upd(s)["value"] for s in trace]
        t_reelay = time.perf_counter() - t0
        # reelay reads bounded operators' windows before time 0 as false; compare after the
        # largest bound has passed
        same = ours[20:] == theirs[20:]
        us_ours = 1e6 * t_ours / args.ticks
        us_reelay = 1e6 * t_reelay / args.ticks
        us_run = 1e6 * t_run / args.ticks
        print(f"{c.id:<6} {us_ours:>14.3f} {us_reelay:>15.3f} {us_reelay / us_ours:>12.1f}x"
              f"  {same}   run(): {us_run:.3f} µs/step, reelay/run() {us_reelay / us_run:.1f}x")
    bound_cost(mod_for=lambda cs: load_text(render_module(cs, "bench_bounds"), "bench_bounds"),
               ticks=args.ticks)
    if args.baseline:
        compare_baseline(compiled, mod, os.path.abspath(args.baseline), args.ticks,
                         args.rounds)


if __name__ == "__main__":
    main()
