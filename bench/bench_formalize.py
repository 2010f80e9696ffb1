"""Formalization throughput, in-process and as a user runs it.

    python bench/bench_formalize.py [--n 1000] [--repeat 5] [--baseline DIR] [--corpus FILE]

1000 generated FRETish sentences covering all 288 template keys, measured two ways in one run:

* in-process: parse + formalize + print ft, ft_inf and pt (the parser already built), CPU
  time (``time.process_time``) of the best of ``--repeat`` runs;
* end to end: ``fretc FILE --emit ltl --json`` on a file of those sentences, a fresh
  Python process each time, CPU time (user + system) of the child with its start-up
  (imports, the Lark tables) from ``resource.getrusage(RUSAGE_CHILDREN)``; best and median
  of ``--repeat`` runs after one warm-up run (which writes the ``.pyc`` files and fretc's
  disk cache as a user's first run does; that first run is printed too), and the same for
  the single requirement of ``requirements/r1.fret``; beside them the interpreter's own
  start-up (``python -c pass``, same measure), the floor under every fretc command.

Real sentences end to end: the NASA case-study requirements of ``--corpus`` (default
``../shared/corpora/fret_casestudies.jsonl``, JSON lines with ``id`` and ``text``), those
that compile (197 of 198: one uses FRET's reserved ``T``), written as a ``.fret`` file (ids
``C1``, ``C2``, ...) and run as ``fretc FILE --emit ltl --json``, so the figure is not only
our generator's.

The error path: ``requirements/r1.fret`` with a second requirement that does not parse
(``fretc FILE --emit ltl``, exit code 1), what a user pays at every typo.

Start-up, the fixed cost of every run whatever the number of sentences: ``python -c "import
fretc.cli"`` (the command's import) and ``fretc EMPTY.fret --emit ltl`` on an empty file (the
import, the command line's parsing and the compile path's imports, then the "no
requirements" error, exit code 2), same measure, beside the per-sentence figures.

The targets are checked and printed as PASS/FAIL: at least 1500 sentences/s of CPU time
end to end (best run, start-up included; the parser is Lark's LALR parser, nothing written
around it) and under 0.3 s of CPU for ``fretc requirements/r1.fret --emit ltl``; the first
run's figures (empty cache: the Lark tables are built) are printed beside them, not judged.

``PYTHONDONTWRITEBYTECODE`` is dropped from the children's environment (a user's Python
caches bytecode; without it every run would compile fretc's sources again). ``--baseline
DIR`` runs the same commands with another checkout of fretc (e.g. ``git archive main | tar
-x -C DIR``) for a ratio measured in the same run; the timed runs of the two checkouts
alternate, so a change in the machine's load hits both. FRET's own formalizer takes about
35 ms per sentence (``../shared/fretish/README.md``, a published figure, not measured
here). The machine's speed is printed as ``sum(range(1000))`` in µs (the figures of
docs/performance.md were taken at about 20 µs).
"""

from __future__ import annotations

import argparse
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fretc.compiler.instantiate import formula_text, instantiate  # noqa: E402
from fretc.fretish import parse  # noqa: E402

SCOPES = ["", "in m", "when not in m", "only in m", "after m", "before m", "only after m",
          "only before m", "while alt > 10", "during flight mode"]
CONDITIONS = ["", "upon c", "whenever c", "when c & !d", "upon p, or when r", "if x > 3"]
TIMINGS = ["", "immediately", "at the next timepoint", "finally", "eventually", "always",
           "never", "within 5 ticks", "for 3 ticks", "after 2 ticks", "until s", "before s"]
RESPONSES = ["r", "!r | q", "x + 2 * y <= 10", "persisted(3, p) -> q", "a xor b & c",
             "occurs(2, q)"]
LAUNCH = "import sys; from fretc.cli import main; sys.exit(main())"
IMPORT = "import fretc.cli"
CORPUS = ROOT.parent / "shared" / "corpora" / "fret_casestudies.jsonl"


def sentences(n: int, seed: int = 1) -> list:
    rnd = random.Random(seed)
    out = []
    for _ in range(n):
        parts = [rnd.choice(SCOPES), rnd.choice(CONDITIONS), "the sw shall",
                 rnd.choice(TIMINGS), "satisfy", rnd.choice(RESPONSES)]
        out.append(" ".join(p for p in parts if p))
    return out


def corpus_sentences(path: Path) -> list:
    """The texts of the JSON-lines corpus ``path`` (``{"id": ..., "text": ...}`` per line),
    each on one line, that fretc compiles without error (read as a ``.fret`` file and
    compiled in-process: :func:`fretc.compiler.build.compile_entries`)."""
    import json

    from fretc.compiler.build import compile_entries
    from fretc.fretish.files import load_requirements

    texts = []
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.strip():
            text = " ".join(json.loads(line)["text"].split())
            if "#" not in text:  # would start a comment in a .fret file
                texts.append(text)
    with tempfile.TemporaryDirectory(prefix="bench_formalize_") as tmp:
        fret = Path(tmp) / "corpus.fret"
        fret.write_text("".join(f"C{i + 1}: {t}\n" for i, t in enumerate(texts)),
                        encoding="utf-8")
        compiled = compile_entries(load_requirements([str(fret)]))
    ok = {c.id for c in compiled if c.error is None and c.formalization is not None}
    return [t for i, t in enumerate(texts) if f"C{i + 1}" in ok]


def child_cpu(cmd, env, cwd, ok=(0,)) -> float:
    """CPU seconds (user + system) of one child process run to completion (its exit code
    one of ``ok``)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in ok:
        raise SystemExit(f"{' '.join(map(str, cmd))} exited {proc.returncode}:\n"
                         + proc.stderr.decode(errors="replace")[-2000:])
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def command_times(roots, args, repeat: int, caches: dict, launch: str = LAUNCH,
                  ok=(0,)) -> dict:
    """``{label: (first run, [timed runs])}``: CPU seconds of ``fretc ARGS`` (``python -c
    LAUNCH ARGS``) with the fretc of each ``(label, root)`` of ``roots``. The timed runs
    alternate between the roots (fretc, baseline, fretc, ...) so a change in the machine's
    load hits both alike."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cmds = {}
    for label, root in roots:
        e = dict(env, PYTHONPATH=str(root), FRETC_CACHE_DIR=caches[label])
        cmds[label] = ([sys.executable, "-c", launch, *map(str, args)], e, root, ok)
    out = {label: (child_cpu(*cmds[label]), []) for label, _ in roots}
    for _ in range(repeat):
        for label, _root in roots:
            out[label][1].append(child_cpu(*cmds[label]))
    return out


TARGET_RATE = 1500      # sentences/s of CPU, end to end, start-up included
TARGET_R1 = 0.3         # s of CPU for fretc requirements/r1.fret --emit ltl


def in_process(texts, repeat: int) -> list:
    """CPU seconds of parse + formalize + print of ``texts``, one per run."""
    parse(texts[0])  # build the parser once, outside the timing
    runs = []
    for _ in range(repeat):
        t0 = time.process_time()
        for text in texts:
            f = instantiate(parse(text))  # as fretc's compile path (compiler.build)
            formula_text(f, "ft"), formula_text(f, "ft_inf"), formula_text(f, "pt")
        runs.append(time.process_time() - t0)
    return runs


def write_inputs(tmp: str, texts: list, corpus: list) -> dict:
    """The input files of the end-to-end runs, in ``tmp``: ``generated``, ``corpus``,
    ``empty`` and ``typo`` (``requirements/r1.fret`` and a requirement that does not
    parse)."""
    files = {"generated": "".join(f"G{i}: {t}\n" for i, t in enumerate(texts)),
             "corpus": "".join(f"C{i + 1}: {t}\n" for i, t in enumerate(corpus)),
             "empty": "",
             "typo": (ROOT / "requirements/r1.fret").read_text(encoding="utf-8")
             + "R2: the sw shall always satisfy p &\n"}
    out = {}
    for name, text in files.items():
        out[name] = Path(tmp) / f"{name}.fret"
        out[name].write_text(text, encoding="utf-8")
    return out


def end_to_end(roots, files: dict, repeat: int, caches: dict) -> dict:
    """``{measure: {label: (first run, [timed runs])}}`` of every end-to-end command."""
    ltl = ["--emit", "ltl"]
    return {"many": command_times(roots, [files["generated"], *ltl, "--json"], repeat, caches),
            "real": command_times(roots, [files["corpus"], *ltl, "--json"], repeat, caches),
            "one": command_times(roots, [ROOT / "requirements/r1.fret", *ltl], repeat, caches),
            "typo": command_times(roots, [files["typo"], *ltl], repeat, caches, ok=(1,)),
            "import": command_times(roots, [], repeat, caches, launch=IMPORT),
            "empty": command_times(roots, [files["empty"], *ltl], repeat, caches, ok=(2,))}


def report(label: str, m: dict, n: int, n_corpus: int) -> tuple:
    """Print the end-to-end figures of ``label``; returns its best runs (sentences, r1,
    case studies, import, empty file, typo)."""
    (first, e2e), (r1_first, r1) = m["many"][label], m["one"][label]
    (c_first, cs), (_, im), (_, em) = m["real"][label], m["import"][label], m["empty"][label]
    ty = m["typo"][label][1]
    med = statistics.median
    print(f"{label}: `fretc FILE --emit ltl --json`, {n} sentences, fresh process: best "
          f"{min(e2e):.3f} s CPU = {n / min(e2e):.0f} sentences/s, median {med(e2e):.3f} s; "
          f"first run (empty cache) {first:.3f} s")
    print(f"{label}: `fretc FILE --emit ltl --json`, {n_corpus} case-study sentences: best "
          f"{min(cs):.3f} s CPU = {n_corpus / min(cs):.0f} sentences/s, median "
          f"{med(cs):.3f} s; first run {c_first:.3f} s")
    print(f"{label}: `fretc requirements/r1.fret --emit ltl`: best {min(r1):.3f} s CPU, "
          f"median {med(r1):.3f} s; first run {r1_first:.3f} s")
    print(f"{label}: the same with a second requirement that does not parse (exit 1, the "
          f"error path): best {min(ty):.3f} s CPU, median {med(ty):.3f} s")
    print(f"{label}: start-up: `python -c \"{IMPORT}\"` best {min(im):.3f} s CPU, median "
          f"{med(im):.3f} s; `fretc EMPTY.fret --emit ltl` (exit 2) best {min(em):.3f} s, "
          f"median {med(em):.3f} s")
    return (min(e2e), min(r1), min(cs), min(im), min(em), min(ty))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5,
                    help="runs of each measurement; best (and median) reported")
    ap.add_argument("--baseline", type=Path, default=None,
                    help="another fretc checkout to run the same commands with")
    ap.add_argument("--corpus", type=Path, default=CORPUS,
                    help="JSON lines of real requirements ({\"id\", \"text\"}) run end to "
                         "end as a .fret file")
    args = ap.parse_args()
    texts = sentences(args.n)
    corpus = corpus_sentences(args.corpus)
    calib = min(timeit.repeat("sum(range(1000))", number=2000, repeat=5)) / 2000 * 1e6
    print(f"machine: sum(range(1000)) = {calib:.1f} µs (docs/performance.md figures: ~20 µs)")

    runs = in_process(texts, args.repeat)
    best = min(runs)
    print(f"in-process, {args.n} sentences: best {best:.3f} s CPU = {args.n / best:.0f} "
          f"sentences/s (runs: {', '.join(f'{r:.3f}' for r in runs)})")

    roots = [("fretc", ROOT)] + ([("baseline", args.baseline.resolve())]
                                 if args.baseline else [])
    with tempfile.TemporaryDirectory(prefix="bench_formalize_") as tmp:
        files = write_inputs(tmp, texts, corpus)
        caches = {label: tempfile.mkdtemp(prefix="cache_", dir=tmp) for label, _ in roots}
        measured = end_to_end(roots, files, args.repeat, caches)
        results = {label: report(label, measured, args.n, len(corpus)) for label, _ in roots}
        if "baseline" in results:
            a, c = results["fretc"], results["baseline"]
            names = (f"{args.n} sentences", "r1.fret", f"{len(corpus)} case studies",
                     "import fretc.cli", "EMPTY.fret", "r1.fret with a typo")
            print("ratio baseline/fretc (CPU, best runs): " + ", ".join(
                f"{y / x:.2f}x on {name}" for x, y, name in zip(a, c, names)))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    bare = [child_cpu([sys.executable, "-c", "pass"], env, ROOT) for _ in range(args.repeat)]
    print(f"python -c pass (the interpreter's start-up, in every run above): best "
          f"{min(bare):.3f} s CPU, median {statistics.median(bare):.3f} s")
    rate, r1 = args.n / results["fretc"][0], results["fretc"][1]
    print(f"FRET (35 ms each): {1000 / 35:.0f} sentences/s; fretc end to end is "
          f"{rate / (1000 / 35):.0f}x that")
    print(f"{'PASS' if rate >= TARGET_RATE else 'FAIL'}: end to end {rate:.0f} sentences/s "
          f"of CPU (target >= {TARGET_RATE})")
    print(f"{'PASS' if r1 < TARGET_R1 else 'FAIL'}: r1.fret {r1:.3f} s CPU (target < "
          f"{TARGET_R1} s)")


if __name__ == "__main__":
    main()
