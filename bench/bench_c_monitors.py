"""Nanoseconds per step of the C99 monitors (``fretc --emit c``) against the Python monitors
(``--emit monitor``) and reelay (PyPI ``reelay``, C++ with Python bindings) on the same
formulas and trace, and the bytes of state per requirement.

    python bench/bench_c_monitors.py [--trace traces/nominal.csv] [--steps 20000000]
                                     [-r requirements/r1.fret -r requirements/safe_ros.fret]

The trace is a CSV of FRET variables (``fretc audit --write-csv``); the C monitors step it
from arrays in memory (the monitor's cost, not the CSV reader's), built with ``cc -O2``,
``--steps`` steps per requirement timed by ``clock_gettime``; the Python monitors step it by
``step()`` and by ``run()``; reelay's ``discrete_timed_monitor`` runs the same pt formula in
its Rye syntax (``update`` per tick). All in one run on this machine; the ratios are the
measure. R2U2's published figures are quoted for comparison, not measured (no R2U2 here).
Every engine's verdicts are checked equal tick by tick before timing.
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "bench"))

from _c_monitors import c_compiler, write  # noqa: E402
from bench_monitor import to_rye  # noqa: E402

from fretc.compiler.build import compile_entries  # noqa: E402
from fretc.compiler.c_codegen import c_units, emit_c  # noqa: E402
from fretc.compiler.codegen import build_monitor_module  # noqa: E402
from fretc.compiler.ir import Node  # noqa: E402
from fretc.fretish.files import load_requirements  # noqa: E402

#: R2U2's published speed of its C monitor (Johannsen et al., "R2U2 Version 3.0", CAV 2023,
#: as quoted in fretc's issue: 0.27-0.80 µs a step on formulas of 3 to 8 nodes)
R2U2_PUBLISHED = "0.27-0.80 µs/step (C, 3-8 node formulas; R2U2 v3.0, CAV 2023)"


def read_trace(path: Path) -> list[dict]:
    """The ticks of a CSV trace as dicts of every variable: the rows of a sampled trace's
    clocks (column ``tick``) joined by time, those that give every variable kept."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    at: dict[str, dict] = {}
    for r in rows:
        cells = at.setdefault(r.get("time") or str(len(at)), {})
        cells.update({k: v for k, v in r.items() if k not in ("time", "tick") and v})
    names = {k for r in rows for k in r if k not in ("time", "tick")}
    return [{k: (v == "true") if v in ("true", "false") else float(v) for k, v in c.items()}
            for c in at.values() if set(c) == names]


def c_literal(x, ctype: str) -> str:
    if ctype == "bool":
        return "true" if x else "false"
    return repr(float(x))


def driver(units, trace: list[dict], steps: int) -> str:
    """C source timing every monitor of ``units`` over ``trace`` (repeated to ``steps``)."""
    monitors = [m for u in units for m in u.monitors]
    out = ["#define _POSIX_C_SOURCE 199309L"] + [f'#include "{u.stem}.h"' for u in units]
    out += ["#include <stdio.h>", "#include <time.h>", "",
            "static double now(void)", "{", "    struct timespec t;",
            "    clock_gettime(CLOCK_MONOTONIC, &t);",
            "    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;", "}", ""]
    for k, m in enumerate(monitors):
        rows = []
        for state in trace:
            fields = ", ".join(c_literal(state[x.raw_name], x.ctype) for x in m.inputs)
            rows.append("    { " + (fields or "0") + " }")
        out += [f"static const {m.prefix}_inputs trace_{k}[{len(trace)}] = {{",
                ",\n".join(rows), "};", ""]
    out += ["int main(void)", "{", "    volatile unsigned sink = 0;", "    double t0, t;",
            "    long i, n;"]
    n = len(trace)
    for k, m in enumerate(monitors):
        p = m.prefix
        out += ["    {", f"        {p}_state s;", "        unsigned verdicts = 0;",
                # check: the verdicts of one pass, printed for the Python side to compare
                f"        {p}_init(&s);", f"        for (i = 0; i < {n}; i++)",
                f"            verdicts = verdicts * 31u + (unsigned){p}_step(&s, &trace_{k}[i]);",
                "        t0 = now();", f"        for (n = 0; n < {steps}L; ) {{",
                f"            {p}_init(&s);",
                f"            for (i = 0; i < {n} && n < {steps}L; i++, n++)",
                f"                sink += (unsigned){p}_step(&s, &trace_{k}[i]);",
                "        }", "        t = now() - t0;",
                f'        printf("%s %.3f %u %u\\n", {m.upper}_ID, t / {steps}.0, '
                f"(unsigned)sizeof s, verdicts);", "    }"]
    out += ["    return (int)(sink & 0u);", "}", ""]
    return "\n".join(out)


def python_hash(verdicts) -> int:
    h = 0
    for v in verdicts:
        h = (h * 31 + int(bool(v))) & 0xFFFFFFFF
    return h


def time_python(cls, trace, steps: int) -> tuple[float, float, list]:
    """(ns per step by step(), by run(), the verdicts of one pass)."""
    reps = max(1, steps // len(trace))
    m = cls()
    verdicts = [m.step(s) for s in trace]
    step = cls().step  # one monitor over the repeated trace (construction not timed)
    t0 = time.perf_counter()
    for _ in range(reps):
        for s in trace:
            step(s)
    t_step = (time.perf_counter() - t0) / (reps * len(trace)) * 1e9
    run = cls().run
    t0 = time.perf_counter()
    for _ in range(reps):
        run(trace)
    t_run = (time.perf_counter() - t0) / (reps * len(trace)) * 1e9
    assert cls().run(trace) == verdicts
    return t_step, t_run, verdicts


def _predicates(n: Node) -> Node:
    """``n`` with each comparison of a variable and a number as an atom named by its Rye
    predicate (``{x <= 0.5}``)."""
    if n.op == "cmp" and n.args[0].op == "var" and n.args[1].op == "num":
        op = {"=": "==", "!=": "!="}.get(n.name, n.name)
        return Node("ap", name=f"{n.args[0].name} {op} {float(n.args[1].name)!r}")
    if not n.args:
        return n
    return Node(n.op, tuple(_predicates(a) for a in n.args), n.name, n.lo, n.hi)


def time_reelay(pt, trace, steps: int, verdicts) -> float | None:
    """ns per update of reelay on ``pt``; None when it has no Rye form. Its verdicts are
    checked equal to ``verdicts`` after the first 20 ticks (reelay reads a bounded window
    before the first tick as false, FRET as absent)."""
    import reelay

    try:
        pattern = to_rye(_predicates(pt), next(iter(trace[0])))
    except ValueError:
        return None
    reps = max(1, steps // len(trace))
    m = reelay.discrete_timed_monitor(pattern=pattern, condense=False)
    got = [m.update(s)["value"] for s in trace]
    assert got[20:] == [bool(v) for v in verdicts][20:]
    names = sorted(set(re.findall(r"\{(\w+)", pattern)))
    samples = [{k: s[k] for k in names} for s in trace]  # the formula's variables only
    m = reelay.discrete_timed_monitor(pattern=pattern, condense=False)
    update = m.update  # one monitor over the repeated trace (its construction not timed)
    t0 = time.perf_counter()
    for _ in range(reps):
        for s in samples:
            update(s)
    return (time.perf_counter() - t0) / (reps * len(trace)) * 1e9


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trace", default=str(ROOT / "traces/nominal.csv"))
    ap.add_argument("--steps", type=int, default=20_000_000)
    ap.add_argument("--python-steps", type=int, default=400_000)
    ap.add_argument("-r", "--requirements", action="append",
                    default=None)
    args = ap.parse_args()
    reqs = args.requirements or [str(ROOT / "requirements/r1.fret"),
                                 str(ROOT / "requirements/safe_ros.fret")]
    cc = c_compiler()
    if cc is None:
        print("no C compiler: nothing to measure")
        return 2
    compiled = compile_entries(load_requirements(reqs))
    trace = read_trace(Path(args.trace))
    files, skipped = emit_c(compiled)
    units = c_units(compiled)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write(files, folder)
        (folder / "bench.c").write_text(driver(units, trace, args.steps))
        sources = [u.stem + ".c" for u in units] + ["bench.c"]
        subprocess.run([cc, "-std=c99", "-O2", "-o", "bench", *sources, "-lm"], cwd=folder,
                       check=True)
        out = subprocess.run([str(folder / "bench")], capture_output=True, text=True,
                             check=True).stdout
    c_rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()}
    py = {}
    for source in dict.fromkeys(c.entry.source for c in compiled):
        group = [c for c in compiled if c.entry.source == source]
        mm = build_monitor_module(group, "bench_c")
        mod = type(sys)("bench_c")
        exec(compile(mm.text, "bench_c", "exec"), mod.__dict__)
        py.update({c.id: (mod.MONITORS[c.id], c) for c in group if c.id in mod.MONITORS})
    print(f"trace {args.trace}: {len(trace)} ticks; C: {args.steps} steps per requirement "
          f"(cc -O2); R2U2 published: {R2U2_PUBLISHED}")
    print(f"{'req':<5} {'C ns/step':>10} {'state B':>8} {'py step':>9} {'py run':>9} "
          f"{'reelay':>9} {'py/C':>7} {'reelay/C':>9}")
    for rid, (ns, size, vhash) in c_rows.items():
        cls, comp = py[rid]
        t_step, t_run, verdicts = time_python(cls, trace, args.python_steps)
        assert python_hash(verdicts) == int(vhash), rid  # the same verdicts as C
        t_re = time_reelay(comp.formalization.pt, trace, args.python_steps, verdicts)
        ns = float(ns)
        print(f"{rid:<5} {ns:>10.2f} {size:>8} {t_step:>9.0f} {t_run:>9.0f} "
              f"{t_re if t_re is not None else float('nan'):>9.0f} {t_step / ns:>6.0f}x "
              f"{(t_re / ns) if t_re else float('nan'):>8.0f}x")
    for stem, rid, why in skipped:
        print(f"no C monitor for {rid} ({stem}): {why}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
