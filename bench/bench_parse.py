"""Parse rate, in-process (not a test): CPU time per sentence of ``fretish.parse`` on three
inputs, and the same for another checkout of fretc in the same process for a ratio.

    python3 bench/bench_parse.py [--n 1000] [--rounds 10] [--seed 0] [--baseline DIR]

Inputs: this script's generator (varied expressions, ``--n`` sentences), the 1000 sentences
of ``bench/bench_formalize.py`` (all template keys) and the NASA case-study requirements
that parse (``../shared/corpora/fret_casestudies.jsonl``, real text). Each input is cut in
chunks of 100 sentences; each chunk is timed ``--rounds`` times (``time.process_time``) and
its best time kept, so a burst of load on the machine costs one sample, not the figure.

``--baseline DIR`` (e.g. ``git archive main | tar -x -C DIR``) imports ``DIR/fretish`` as
a package of another name (``fretish_baseline``, copied to a temporary folder; its modules
import one another relatively) and times it on the same chunks, alternating with ours, so
both see the same machine; the ratio ours/baseline is printed per input.
"""

from __future__ import annotations

import argparse
import importlib
import json
import random
import re
import shutil
import sys
import tempfile
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from fretc.fretish import parse  # noqa: E402

CASE_STUDIES = ROOT / ".." / "shared" / "corpora" / "fret_casestudies.jsonl"

SCOPES = ["", "in m", "during flight mode", "when in mode m", "if not in m", "unless in m",
          "except during m", "except while alt > 10", "only in m", "only while x < 3",
          "after m", "before alt > 10", "only after m", "only before m", "while ready"]
QUALIFIERS = ["upon", "when", "if", "where", "unless", "whenever"]
TIMINGS = ["", "immediately", "initially", "at the first timepoint", "at the same timepoint",
           "at the next timepoint", "finally", "at the last timepoint", "eventually",
           "always", "never", "within 5 ticks", "for 2 seconds", "after 3 ticks",
           "until stop", "before done & ok"]
ATOMS = ["p", "q", "too_close", "ROS.state = 2", "x > 3", "speed <= 0.5", "persisted(3, p)",
         "occurred(2, q)", "preBool(false, p)", "absReal(x - y) < 1e-3", "FTP", "true"]
OPS = ["&", "|", "->", "xor", "<->"]


def expression(rng: random.Random, depth: int = 0) -> str:
    if depth > 2 or rng.random() < 0.4:
        atom = rng.choice(ATOMS)
        return f"!{atom}" if rng.random() < 0.15 and " " not in atom else atom
    left, right = expression(rng, depth + 1), expression(rng, depth + 1)
    text = f"{left} {rng.choice(OPS)} {right}"
    return f"({text})" if rng.random() < 0.5 else text


def sentence(rng: random.Random) -> str:
    parts = [rng.choice(SCOPES)]
    if rng.random() < 0.6:
        conds = [f"{rng.choice(QUALIFIERS)} {expression(rng, 2)}"
                 for _ in range(rng.choice([1, 1, 1, 2]))]
        parts.append(" and ".join(conds))
    parts.append(rng.choice(["the sw", "agilex_agent", "the controller"]) + " shall")
    if rng.random() < 0.05:
        parts.append("with probability >= 0.9")
    parts.append(rng.choice(TIMINGS))
    parts.append("satisfy " + expression(rng))
    return " ".join(p for p in parts if p) + rng.choice(["", "."])


def _parses(text: str) -> bool:
    try:
        parse(text)
        return True
    except Exception:  # noqa: BLE001 - an invalid case-study sentence is left out
        return False


def inputs(n: int, seed: int) -> dict:
    """name -> list of sentences."""
    from bench_formalize import sentences as formalize_sentences
    rng = random.Random(seed)
    out = {"bench_parse generator": [sentence(rng) for _ in range(n)],
           "bench_formalize sentences": formalize_sentences(1000)}
    if CASE_STUDIES.exists():
        texts = [json.loads(line)["text"] for line in CASE_STUDIES.open(encoding="utf-8")]
        out["case studies (valid)"] = [t for t in texts if _parses(t)]
    return out


def load_baseline(path: Path, tmp: str):
    """``parse`` of the checkout at ``path``, imported as package ``fretish_baseline``."""
    src = path / "fretish"
    for f in src.glob("*.py"):
        if re.search(r"^\s*(from|import)\s+fretish\b", f.read_text(encoding="utf-8"), re.M):
            raise SystemExit(f"{f}: imports fretish absolutely; cannot load it beside ours")
    shutil.copytree(src, Path(tmp) / "fretish_baseline",
                    ignore=shutil.ignore_patterns("__pycache__"))
    sys.path.insert(0, tmp)
    return importlib.import_module("fretish_baseline").parse


def best_times(runs: dict, texts: list, rounds: int) -> dict:
    """name -> sum over 100-sentence chunks of the best CPU time of each chunk."""
    chunks = [texts[i:i + 100] for i in range(0, len(texts), 100)]
    best = {name: [float("inf")] * len(chunks) for name in runs}
    for run in runs.values():       # warm-up: tables loaded, words known
        for t in texts:
            run(t)
    for _ in range(rounds):
        for j, chunk in enumerate(chunks):
            for name, run in runs.items():
                c0 = time.process_time()
                for t in chunk:
                    run(t)
                best[name][j] = min(best[name][j], time.process_time() - c0)
    return {name: sum(v) for name, v in best.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--baseline", type=Path, default=None,
                    help="another fretc checkout, timed in the same process for a ratio")
    args = ap.parse_args()
    t0 = time.perf_counter()
    parse("the sw shall satisfy p")             # loads (or builds) the parser tables once
    build = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        runs = {"fretc": parse}
        if args.baseline is not None:
            runs["baseline"] = load_baseline(args.baseline, tmp)
        print(f"parser load: {build * 1000:.0f} ms")
        for label, texts in inputs(args.n, args.seed).items():
            best = best_times(runs, texts, args.rounds)
            chars = sum(map(len, texts)) / len(texts)
            line = (f"{label}: {len(texts)} sentences (mean {chars:.0f} chars), CPU per "
                    f"sentence: fretc {best['fretc'] / len(texts) * 1e6:.1f} us "
                    f"({len(texts) / best['fretc']:,.0f}/s)")
            if "baseline" in best:
                line += (f", baseline {best['baseline'] / len(texts) * 1e6:.1f} us; "
                         f"ratio fretc/baseline {best['fretc'] / best['baseline']:.2f}")
            print(line)
    calib = min(timeit.repeat("sum(range(1000))", number=2000, repeat=5)) / 2000 * 1e6
    print(f"machine speed: sum(range(1000)) takes {calib:.1f} us here "
          "(about 5-10 us on an idle modern x86 core)")


if __name__ == "__main__":
    main()
