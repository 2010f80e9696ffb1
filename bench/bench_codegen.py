"""Monitor generation and generated-module import, as a user runs them.

    python bench/bench_codegen.py [--baseline DIR] [--quick] [--import-only]

Measured in one run, each in a fresh Python process with an empty fretc cache
(``FRETC_CACHE_DIR`` set to a new folder: "cold") unless said otherwise, CPU time (user +
system) of the child from ``resource.getrusage(RUSAGE_CHILDREN)``:

1. ``fretc FILE --emit monitor`` on the 696 distinct sentences of
   ``shared/fretish/fret_trace_verdicts.jsonl``: CPU per requirement on average, cold and
   warm (second run, same cache), and the slowest requirement (``monitor_source`` timed
   requirement by requirement in a cold child);
2. the slowest requirement among the 288 template keys with every bound at 12 ticks (the
   largest Spot builds), cold; and two known worst cases of the old code:
   ``in m mode whenever p ... within 12 ticks`` and ``persists(99999999999,
   occurs(99999999999, p))``;
3. importing a generated module of 10,000 requirements (``bench_formalize``'s generator):
   CPU time and peak RSS of a child that imports it (first import compiles it; the second
   uses the ``.pyc``), beside a child that only starts Python, and of a child that makes one
   object of every class (which compiles the step code of every shape); with
   ``--baseline``, the same for the module the baseline generates from the same file; and
   where the CPU time of ``--emit monitor`` on the 696 sentences of (1) goes in one
   process, cold then warm (imports, formalization, LTL3 automata, step code, Jinja
   rendering, the module check's ``compile()`` and the rest of the check);
4. the generated module text of (1) cold and warm: byte-identical or not.

``--baseline DIR`` runs (1) and the two worst cases with another checkout of fretc (e.g.
``git archive main | tar -x -C DIR``) for ratios; it takes minutes (the old code needs about
51 s on (1) and 137 s / 1.5 GB on the ``persists`` case on an idle machine). Without it the
figures the issue recorded for the old code are printed as the baseline.
``--quick`` skips (2)'s 288-key sweep and uses 2,000 requirements in (3).
``--import-only`` runs (3) alone.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

LAUNCH = "import sys; from fretc.cli import main; sys.exit(main())"
WORST = {
    "W1": "in m mode whenever p the sw shall within 12 ticks satisfy q",
    "W2": "the sw shall always satisfy persists(99999999999, occurs(99999999999, p))",
}
ISSUE_BASELINE = {"696": "51 s CPU (73 ms per requirement)", "W1": "6.5 s, 235 MB",
                  "W2": "137 s, 1.5 GB", "import10k": "20 s, 1.85 GB"}
#: The figures of the previous session (docs/performance.md, final tree, idle machine,
#: sum(range(1000)) 16-23 µs), printed beside today's.
LAST_SESSION = {"696": "20.0 ms cold, 3.4 ms warm per requirement",
                "slowest": "0.65 s ('only in mm whenever cc the sw shall after 8 ticks "
                           "satisfy rr'); 288 keys at 12 ticks: 0.54 s"}
#: The targets for monitor generation.
TARGET_MS_PER_REQ = 10.0
TARGET_MAX_S = 1.0
#: The target for importing a generated module of 10,000 requirements (first import).
IMPORT_MAX_S, IMPORT_MAX_MB = 2.0, 300


def verdict(ok: bool) -> str:
    return "PASS" if ok else "FAIL"

# Where the CPU time of --emit monitor goes, in this process (cold or warm: the cache folder
# of the environment); prints JSON. The LTL3 automata (codegen.ltl3_automata) and the
# compile() calls of the module check are timed inside monitor_source and check_module.
PHASES = r"""
import json, sys, time
from pathlib import Path
t0 = time.process_time()
from fretc.compiler import codegen
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
t1 = time.process_time()
spent = {"automata": 0.0, "compile": 0.0}

def timed(what, fn):
    def wrapper(*args, **kwargs):
        t = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[what] += time.process_time() - t
    return wrapper

codegen.ltl3_automata = timed("automata", codegen.ltl3_automata)
codegen.compile = timed("compile", compile)  # the module global shadows the builtin
cs = compile_entries(load_requirements([Path(sys.argv[1])]))
t2 = time.process_time()
sources, skipped = [], []
for i, c in enumerate(cs):
    try:
        sources.append(codegen.monitor_source(c, i))
    except codegen.CodegenError as exc:
        skipped.append((c.id, str(exc)))
t3 = time.process_time()
text = codegen._render(sources, skipped, "m")
t4 = time.process_time()
codegen.check_module(text, "m", cache=True)  # as build_monitor_module does
t5 = time.process_time()
print(json.dumps({"imports": t1 - t0, "formalize": t2 - t1,
                  "LTL3 automata": spent["automata"],
                  "step code": t3 - t2 - spent["automata"], "render": t4 - t3,
                  "check: compile()": spent["compile"],
                  "check: names, load, steps": t5 - t4 - spent["compile"],
                  "n": len(cs)}))
"""

# Times each requirement's monitor_source in this (cold) process; prints JSON.
PER_REQ = r"""
import json, sys, time
from pathlib import Path
from fretc.compiler.build import compile_entries
from fretc.compiler.codegen import CodegenError, monitor_source
from fretc.fretish.files import load_requirements
cs = compile_entries(load_requirements([Path(sys.argv[1])]))
out = []
for i, c in enumerate(cs):
    if c.formalization is None:
        continue
    t = time.process_time()
    try:
        monitor_source(c, i)
    except CodegenError:
        pass
    out.append((time.process_time() - t, c.text))
print(json.dumps(out))
"""


def _env(root: Path, cache: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(root)
    env["FRETC_CACHE_DIR"] = cache
    return env


def run_child(cmd, env, cwd):
    """(CPU seconds, peak RSS MB, stdout) of one child run to completion."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(map(str, cmd))} exited {proc.returncode}:\n"
                         + proc.stderr.decode(errors="replace")[-3000:])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # ru_maxrss of RUSAGE_CHILDREN is the largest child so far: only meaningful when it grew
    return cpu, after.ru_maxrss / 1024, proc.stdout


def fretc(root, args, cache, tmp):
    return run_child([sys.executable, "-c", LAUNCH, *map(str, args)], _env(root, cache), tmp)


def rss_child(cmd, env, cwd):
    """(CPU s, peak RSS MB) of a child, RSS measured by the child itself at exit."""
    code = ("import resource, sys, time; t = time.process_time(); "
            + cmd + "; print(time.process_time() - t, "
            "resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)")
    cpu, _, out = run_child([sys.executable, "-c", code], env, cwd)
    t, rss = out.decode().split()[-2:]
    return cpu, float(t), float(rss)


def verdict_sentences() -> list:
    rows = [json.loads(l) for l in (SHARED / "fretish/fret_trace_verdicts.jsonl").open()]
    return list(dict.fromkeys(c["sentence"] for r in rows for c in r["cases"]))


def template_sentences(n: int) -> list:
    """One sentence per template key (8 scopes x 3 conditions x 12 timings), bound ``n``."""
    scopes = ["", "in m", "not in m", "only in m", "after m", "before m", "only after m",
              "only before m"]
    scopes[2] = "when not in m"
    conditions = ["", "upon c", "whenever c"]
    timings = ["immediately", "at the next timepoint", "finally", "eventually", "always",
               "never", f"within {n} ticks", f"for {n} ticks", f"after {n} ticks",
               "until s", "before s", ""]
    return [" ".join(p for p in (s, c, "the sw shall", t, "satisfy r") if p)
            for s in scopes for c in conditions for t in timings]


def write_fret(path: Path, texts, prefix="S") -> Path:
    path.write_text("".join(f"{prefix}{i}: {t}\n" for i, t in enumerate(texts)),
                    encoding="utf-8")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, default=None)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--import-only", action="store_true")
    args = ap.parse_args()
    calib = min(timeit.repeat("sum(range(1000))", number=2000, repeat=5)) / 2000 * 1e6
    print(f"machine: sum(range(1000)) = {calib:.1f} µs (docs/performance.md figures: ~20 µs)")
    roots = [("fretc", ROOT)] + ([("baseline", args.baseline.resolve())]
                                 if args.baseline else [])
    with tempfile.TemporaryDirectory(prefix="bench_codegen_") as tmp_s:
        tmp = Path(tmp_s)
        texts = verdict_sentences()
        f696 = write_fret(tmp / "verdicts.fret", texts, "T")
        figures = {}
        if args.import_only:
            _import_section(roots, 2000 if args.quick else 10000, f696, tmp)
            return
        for label, root in roots:
            cold = tempfile.mkdtemp(prefix="cache_", dir=tmp)
            out_cold, out_warm = tmp / f"{label}_cold.py", tmp / f"{label}_warm.py"
            c1, _, _ = fretc(root, [f696, "--emit", "monitor", "-o", out_cold], cold, tmp)
            c2, _, _ = fretc(root, [f696, "--emit", "monitor", "-o", out_warm], cold, tmp)
            same = out_cold.read_bytes() == out_warm.read_bytes()
            figures[label] = c1
            ms = 1000 * c1 / len(texts)
            print(f"[1] {label}: `fretc FILE --emit monitor`, {len(texts)} requirements: "
                  f"cold {c1:.2f} s CPU = {ms:.1f} ms each; warm "
                  f"{c2:.2f} s = {1000 * c2 / len(texts):.1f} ms each"
                  + (f"; target <= {TARGET_MS_PER_REQ:.0f} ms cold: "
                     f"{verdict(ms <= TARGET_MS_PER_REQ)}" if label == "fretc" else ""))
            print(f"[4] {label}: module of (1) cold == warm (byte-identical): "
                  f"{verdict(same)}")
            if label == "fretc":
                cpu, per, worst = _per_requirement(root, f696, tmp)
                print(f"[1] fretc: slowest requirement (cold, monitor_source): "
                      f"{worst[0]:.3f} s CPU ({worst[1]!r}); mean "
                      f"{1000 * sum(t for t, _ in per) / len(per):.1f} ms; target <= "
                      f"{TARGET_MAX_S:.0f} s: {verdict(worst[0] <= TARGET_MAX_S)}")
                print(f"[1] last session: {LAST_SESSION['696']}; slowest "
                      f"{LAST_SESSION['slowest']}")
            for key, text in WORST.items():
                fw = write_fret(tmp / f"{key}.fret", [text], key)
                cache = tempfile.mkdtemp(dir=tmp)
                cpu, _, rss = _worst_case(root, fw, tmp, cache)
                warm, _, _ = _worst_case(root, fw, tmp, cache)  # start-up, parse, render
                own = cpu - warm
                print(f"[2] {label}: {text!r}: {cpu:.2f} s CPU, peak RSS {rss:.0f} MB "
                      f"(cold cache, fresh process, start-up included; warm {warm:.2f} s, "
                      f"so {own:.2f} s filling the cache: Lark tables and automata)"
                      + (f"; target <= {TARGET_MAX_S:.0f} s: {verdict(own <= TARGET_MAX_S)}"
                         if label == "fretc" else "")
                      + (f"; old code per the issue: {ISSUE_BASELINE[key]}"
                         if label == "fretc" else ""))
        if args.baseline and "baseline" in figures:
            print(f"[1] ratio baseline/fretc, cold: {figures['baseline'] / figures['fretc']:.1f}x")
        print(f"[1] old code per the issue: {ISSUE_BASELINE['696']}")

        if not args.quick:
            ft = write_fret(tmp / "templates12.fret", template_sentences(12), "K")
            cpu, per, worst = _per_requirement(ROOT, ft, tmp)
            over = sum(1 for t, _ in per if t > TARGET_MAX_S)
            print(f"[2] fretc: 288 template keys, bounds 12 ticks, cold: total {cpu:.2f} s "
                  f"CPU, slowest {worst[0]:.3f} s ({worst[1]!r}), {over} over "
                  f"{TARGET_MAX_S:.0f} s: {verdict(over == 0)}")

        _import_section(roots, 2000 if args.quick else 10000, f696, tmp)


def _import_section(roots, n: int, f696: Path, tmp: Path) -> None:
    """Section (3): import of a generated module of ``n`` requirements, per root; where
    ``--emit monitor``'s CPU time goes on the 696 sentences."""
    from bench_formalize import sentences
    fbig = write_fret(tmp / "big.fret", sentences(n, seed=3), "R")
    for label, root in roots:
        cache = tempfile.mkdtemp(prefix="cache_", dir=tmp)
        mod_dir = tmp / f"mod_{label}"
        mod_dir.mkdir()
        cpu_gen, _, _ = fretc(root, [fbig, "--emit", "monitor", "-o", mod_dir / "big.py"],
                              cache, tmp)
        env = _env(mod_dir, cache)
        _, t0, rss0 = rss_child("pass", env, mod_dir)
        _, t1, rss1 = rss_child("import big; assert big.MONITORS", env, mod_dir)
        _, t2, rss2 = rss_child("import big; assert big.MONITORS", env, mod_dir)
        _, t3, rss3 = rss_child("import big\nfor c in big.MONITORS.values(): c()", env,
                                mod_dir)
        size = (mod_dir / "big.py").stat().st_size / 1e6
        print(f"[3] {label}: module of {n} requirements ({size:.1f} MB, generated cold in "
              f"{cpu_gen:.1f} s CPU): import {t1:.2f} s CPU / {rss1:.0f} MB peak RSS (first, "
              f"compiles), {t2:.2f} s / {rss2:.0f} MB (from .pyc); then one object of every "
              f"class {t3 - t2:.2f} s more ({t3:.2f} s / {rss3:.0f} MB in all); bare Python "
              f"{rss0:.0f} MB"
              + ("" if len(roots) > 1 or n != 10000 else
                 f"; old code per the issue (10,000): {ISSUE_BASELINE['import10k']}")
              + ("" if label != "fretc" or n != 10000 else
                 f"; target first import < {IMPORT_MAX_S:.0f} s and < {IMPORT_MAX_MB} MB: "
                 f"{verdict(t1 < IMPORT_MAX_S and rss1 < IMPORT_MAX_MB)}"))
    cache = tempfile.mkdtemp(dir=tmp)
    for state in ("cold", "warm"):  # warm: the same cache folder, second run
        _, _, out = run_child([sys.executable, "-c", PHASES, f696], _env(ROOT, cache), tmp)
        ph = json.loads(out)
        total = sum(v for k, v in ph.items() if k != "n")
        print(f"[3] fretc: where the CPU time of `--emit monitor` goes, {ph['n']} "
              f"requirements in one {state} process, {1000 * total / ph['n']:.2f} ms each:")
        for k, v in ph.items():
            if k != "n":
                print(f"[3]     {k:<28} {1000 * v / ph['n']:6.2f} ms/req "
                      f"({100 * v / total:3.0f}%)")


def _per_requirement(root: Path, fret_file: Path, tmp: Path):
    """CPU s of a cold child timing each requirement of ``fret_file`` (PER_REQ), the list of
    (seconds, requirement text) pairs it prints, and the slowest pair."""
    cpu, _, out = run_child([sys.executable, "-c", PER_REQ, fret_file],
                            _env(root, tempfile.mkdtemp(dir=tmp)), tmp)
    per = json.loads(out)
    return cpu, per, max(per)


def _worst_case(root: Path, fret_file: Path, tmp: Path, cache: str):
    """(CPU s, in-child seconds, peak RSS MB) of ``fretc FILE --emit monitor`` with the
    fretc cache folder ``cache`` (cold when new)."""
    env = _env(root, cache)
    code = ("from fretc.cli import main\n"
            "try:\n    main([%r, '--emit', 'monitor', '-o', %r])\n"
            "except SystemExit:\n    pass" % (str(fret_file), str(tmp / "worst.py")))
    code = ("import resource, sys, time\nt = time.process_time()\n" + code
            + "\nprint(time.process_time() - t, "
              "resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)")
    cpu, _, out = run_child([sys.executable, "-c", code], env, tmp)
    t, rss = out.decode().split()[-2:]
    return cpu, float(t), float(rss)


if __name__ == "__main__":
    main()
