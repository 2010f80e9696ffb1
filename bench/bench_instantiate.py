"""Formula construction + printing: per-template-key instantiation against the full IR build,
in one run on the same sentences; and what ``fretc FILE --emit ltl --json`` does with a
parsed file (instantiate, print, write the JSON), against another checkout.

    python bench/bench_instantiate.py [--n 1000] [--repeat 5] [--baseline DIR]

The sentences are bench_formalize.py's (all 288 template keys), parsed once outside the
timings. For each requirement both paths produce what ``fretc FILE --emit ltl --json``
prints: ft, ft_inf, pt (FRET/SMV) and the Spot text of ft and ft_inf.

* full: :func:`fretc.compiler.semantics.formalize` then the printers (the path before
  :mod:`fretc.compiler.instantiate`);
* template: :func:`fretc.compiler.instantiate.instantiate` then
  :func:`fretc.compiler.instantiate.formula_text`; "cold" is the first pass of the process
  (each template key's file of ``compiler/table/`` read on its first use), "warm" the best
  later pass.

CPU time (``time.process_time``), best of ``--repeat`` passes, the cyclic garbage collector
paused as ``fretc --emit ltl`` pauses it; the ratio full/template is printed.

Then the per-sentence part of ``--emit ltl --json`` after parsing, on two inputs: the
sentences above (``generated.fret``) and the 198 real requirements of
``../shared/corpora/fret_casestudies.jsonl`` (``corpus.fret``, whitespace runs joined; the
generator repeats its expressions, the corpus mostly does not). Each pass reads the file
(:func:`fretc.fretish.files.load_requirements`, untimed: fresh entries, nothing cached from the
pass before), then times :func:`fretc.compiler.build.compile_entries` and the JSON text of
``--json`` (``fretc.compile.ltl_json``, or ``json_indent2`` of ``to_json()`` in a checkout
without it). It runs in a child process per checkout (this one, and ``--baseline DIR``,
e.g. ``git archive main | tar -x -C DIR``), the children alternating, ``--rounds`` times;
the best pass of all is printed in µs/sentence with the ratio baseline/this, and whether
the two JSON texts are byte-identical.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bench_formalize import sentences  # noqa: E402
from fretc.compiler.instantiate import InstantiatedFormalization, formula_text, instantiate  # noqa: E402
from fretc.compiler.printers import to_smv, to_spot  # noqa: E402
from fretc.compiler.semantics import formalize  # noqa: E402
from fretc.fretish import parse  # noqa: E402

FORMS = ("ft", "ft_inf", "pt", "ft_spot", "ft_inf_spot")


def full(reqs) -> None:
    for r in reqs:
        f = formalize(r)
        to_smv(f.ft), to_smv(f.ft_inf), to_smv(f.pt, ftp="(Z FALSE)")
        to_spot(f.ft), to_spot(f.ft_inf)


def template(reqs) -> None:
    for r in reqs:
        f = instantiate(r)
        for which in FORMS:
            formula_text(f, which)


def timed(fn, reqs) -> float:
    t0 = time.process_time()
    fn(reqs)
    return time.process_time() - t0


#: run in a child with a checkout first on sys.path: argv = [root, repeat, file...]; prints
#: one JSON line {file: [best CPU seconds, entries, crc32 of the JSON text]}
CHILD = r"""
import gc, json, sys, time, zlib
root, repeat, files = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
sys.path.insert(0, root)
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
import fretc.cli.compile as fc

def emit(compiled):
    if hasattr(fc, "ltl_json"):
        return fc.ltl_json(compiled)
    return fc.json_indent2([c.to_json() for c in compiled])

out = {}
for f in files:
    emit(compile_entries(load_requirements([f])))  # templates read, imports done
    best = None
    for _ in range(repeat):
        entries = load_requirements([f])
        gc.collect()
        gc.disable()
        t0 = time.process_time()
        text = emit(compile_entries(entries))
        dt = time.process_time() - t0
        gc.enable()
        best = dt if best is None else min(best, dt)
    out[f] = [best, len(entries), zlib.crc32(text.encode())]
print(json.dumps(out))
"""


def write_inputs(folder: Path, n: int) -> list:
    """``generated.fret`` (:func:`sentences`) and ``corpus.fret`` (the case studies)."""
    gen = folder / "generated.fret"
    gen.write_text("".join(f"G{i}: {t}\n" for i, t in enumerate(sentences(n))),
                   encoding="utf-8")
    corpus = folder / "corpus.fret"
    rows = (ROOT.parent / "shared" / "corpora" / "fret_casestudies.jsonl").read_text(
        encoding="utf-8").splitlines()
    corpus.write_text("".join(f"C{i}: {' '.join(json.loads(r)['text'].split())}\n"
                              for i, r in enumerate(rows) if r.strip()), encoding="utf-8")
    return [gen, corpus]


def pipeline(roots, files, repeat: int, rounds: int) -> dict:
    """``{label: {file: [best s, entries, crc]}}`` over ``rounds`` alternating children."""
    env = dict(os.environ, FRETC_CACHE_DIR=tempfile.mkdtemp(prefix="bench_inst_cache_"))
    best: dict = {}
    for _ in range(rounds):
        for label, root in roots:
            proc = subprocess.run([sys.executable, "-c", CHILD, str(root), str(repeat),
                                   *map(str, files)], env=env, cwd=root,
                                  capture_output=True, text=True)
            if proc.returncode != 0:
                raise SystemExit(f"{label}: child failed:\n{proc.stderr[-2000:]}")
            for f, row in json.loads(proc.stdout).items():
                old = best.setdefault(label, {}).get(f)
                if old is None or row[0] < old[0]:
                    best[label][f] = row
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3,
                    help="children per checkout (alternating) for the --json pipeline")
    ap.add_argument("--baseline", type=Path, default=None,
                    help="another fretc checkout to run the --json pipeline with")
    args = ap.parse_args()
    roots = [("fretc", ROOT)] + ([("baseline", args.baseline.resolve())]
                                 if args.baseline else [])
    with tempfile.TemporaryDirectory(prefix="bench_instantiate_") as tmp:
        files = write_inputs(Path(tmp), args.n)
        best = pipeline(roots, files, args.repeat, args.rounds)
    print("instantiate + printed forms + JSON text of `--emit ltl --json` (parsed entries), "
          f"best of {args.rounds} x {args.repeat} passes:")
    for f in files:
        ours = best["fretc"][str(f)]
        line = f"  {f.name} ({ours[1]} requirements): {ours[0] / ours[1] * 1e6:.1f} µs/sentence"
        if "baseline" in best:
            base = best["baseline"][str(f)]
            line += (f"; baseline {base[0] / base[1] * 1e6:.1f} µs/sentence, ratio "
                     f"baseline/this {base[0] / ours[0]:.2f}x, JSON "
                     f"{'identical' if base[2] == ours[2] else 'DIFFERS'}")
        print(line)
    reqs = [parse(t) for t in sentences(args.n)]
    gc.collect()
    gc.disable()
    cold = timed(template, reqs)
    runs = {"full": [], "template": []}
    for _ in range(args.repeat):
        runs["full"].append(timed(full, reqs))
        runs["template"].append(timed(template, reqs))
    used = sum(isinstance(instantiate(r), InstantiatedFormalization) for r in reqs)
    bf, bt = min(runs["full"]), min(runs["template"])
    n = args.n
    print(f"{n} sentences, {used} from a template ({n - used} fell back to the full build)")
    print(f"full build + printers: {bf * 1e3:.1f} ms CPU = {bf / n * 1e6:.0f} µs/sentence")
    print(f"template, warm:        {bt * 1e3:.1f} ms CPU = {bt / n * 1e6:.0f} µs/sentence")
    print(f"template, cold (first pass of this process): {cold * 1e3:.1f} ms CPU")
    print(f"ratio full/template (warm): {bf / bt:.2f}x; (cold): {bf / cold:.2f}x")


if __name__ == "__main__":
    main()
