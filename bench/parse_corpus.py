"""Requirement files for ``bench/same_parse.py``: many good and bad FRETish sentences.

    python3 bench/parse_corpus.py OUT_DIR [--seed 1] [--mutations 6000] [--expressions 5000]

Writes ``OUT_DIR/all.fret`` (one sentence per line) and ``OUT_DIR/multi.json`` (a FRET JSON
export whose texts span several lines, so spans and error positions cross lines): the
1000 sentences of ``bench/bench_formalize.py``, the NASA case studies
(``../shared/corpora/fret_casestudies.jsonl``), FRET's vectors
(``../shared/fretish/fret_vectors*.jsonl``), random mutations of those (a piece inserted,
a word deleted, two words swapped, the text cut, a character replaced) and random
expressions (every operator, "!", "~" and "-" in any position, if-then, occurrences,
reserved words), so most syntax and expression errors occur. Deterministic for a seed.
"""

from __future__ import annotations

import argparse
import json
import random
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
sys.path.insert(0, str(ROOT / "bench"))

from bench_formalize import sentences  # noqa: E402

PIECES = ["&", "|", "!", "~", "(", ")", ",", ".", "-", "+", "*", "=", "==", "<=", "<", "->",
          "=>", "<->", "shall", "satisfy", "the", "within", "for", "after", "until", "3",
          "2.5", "ticks", "tickz", "seconds", "and", "or", "not", "if", "then", "upon",
          "when", "in", "mode", "only", "T", "X", "what", "globally", "is", "true", "false",
          "with", "probability", ">= 0.5", "é", '"', '"q"', "%", "@", "  ", "0x", "^", "-3",
          "- 3", "!-", "-!", "mod", "/", ">", "!=", "xor", "<=>", "~(", "persisted(",
          "occurs(2,", "preBool(3, p)", "next", "previous", "occurrence", "of",
          "at the next occurrence of p,", "if a then", "!if b then", "a < b <"]
ATOMS = ["p", "q", "x", "y", "3", "2.5", "-1", "true", "FALSE", "f(x, y)", "(p)", "(x + 1)",
         "preBool(false, p)", '"q r"', "T", "what", "-x", "- 2", "!p", "~q", "-!p", "1e3"]
OPS = ["&", "|", "->", "=>", "<->", "<=>", "xor", "=", "!=", "<", "<=", ">", ">=", "+", "-",
       "*", "/", "mod", "^"]


def good_sentences() -> list:
    """The valid sentences the others are made from, each on one line."""
    texts = sentences(1000)
    corpus = SHARED / "corpora" / "fret_casestudies.jsonl"
    texts += [json.loads(line)["text"] for line in corpus.open(encoding="utf-8")
              if line.strip()]
    for name in ("fret_vectors.jsonl", "fret_vectors_functions.jsonl"):
        for line in (SHARED / "fretish" / name).open(encoding="utf-8"):
            if line.strip() and isinstance(json.loads(line).get("text"), str):
                texts.append(json.loads(line)["text"])
    return [" ".join(t.split()) for t in texts]


def expression(rnd: random.Random, depth: int = 0) -> str:
    """A random expression text, valid or not."""
    k = rnd.random()
    if depth > 3 or k < 0.3:
        return rnd.choice(ATOMS)
    if k < 0.45:
        return rnd.choice(["!", "~", "-", "- ", "!!", "-!", "!-"]) + expression(rnd, depth + 1)
    if k < 0.55:
        return "(" + expression(rnd, depth + 1) + ")"
    if k < 0.62:
        return f"if {expression(rnd, depth + 1)} then {expression(rnd, depth + 1)}"
    if k < 0.66:
        return (f"at the {rnd.choice(['previous', 'next'])} occurrence of "
                f"{expression(rnd, depth + 1)}, {expression(rnd, depth + 1)}")
    return f"{expression(rnd, depth + 1)} {rnd.choice(OPS)} {expression(rnd, depth + 1)}"


def mutate(rnd: random.Random, text: str) -> str:
    """``text`` with one to three random edits."""
    for _ in range(rnd.randint(1, 3)):
        words = text.split(" ")
        op = rnd.choice(["insert", "delete", "swap", "cut", "char"])
        i = rnd.randint(0, max(0, len(words) - 1))
        if op == "insert":
            words.insert(i, rnd.choice(PIECES))
        elif op == "delete" and len(words) > 1:
            del words[i]
        elif op == "swap" and len(words) > 1:
            j = rnd.randint(0, len(words) - 1)
            words[i], words[j] = words[j], words[i]
        elif op == "cut":
            words = words[:i + 1]
        text = " ".join(words)
        if op == "char" and text:
            k = rnd.randint(0, len(text) - 1)
            text = text[:k] + rnd.choice(PIECES) + text[k + 1:]
    return text


def corpus(rnd: random.Random, mutations: int, expressions: int) -> list:
    """Good sentences, their mutations and sentences around random expressions."""
    good = good_sentences()
    texts = good + [mutate(rnd, rnd.choice(good)) for _ in range(mutations)]
    for _ in range(expressions):
        if rnd.random() < 0.6:
            texts.append(f"the sw shall always satisfy {expression(rnd)}")
        else:
            timing = rnd.choice(["", "within 3 ticks", f"until {expression(rnd)}"])
            texts.append(f"{rnd.choice(['upon', 'when', 'whenever', 'unless'])} "
                         f"{expression(rnd)} the sw shall {timing} satisfy {expression(rnd)}")
    return [t.replace("#", "") for t in texts if t.strip()]  # "#" starts a .fret comment


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mutations", type=int, default=6000)
    ap.add_argument("--expressions", type=int, default=5000)
    args = ap.parse_args()
    rnd = random.Random(args.seed)
    texts = corpus(rnd, args.mutations, args.expressions)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "all.fret").write_text("".join(f"S{i}: {t}\n" for i, t in enumerate(texts)),
                                       encoding="utf-8")
    multi = []
    for i, text in enumerate(texts[::7]):
        words = text.split(" ")
        seps = [rnd.choice([" ", "\n", "\n  ", " \n"]) for _ in words[1:]] + [""]
        multi.append({"reqid": f"M{i}", "fulltext": "".join(w + s for w, s in zip(words, seps))})
    (args.out / "multi.json").write_text(json.dumps(multi, indent=1), encoding="utf-8")
    print(f"{args.out}/all.fret: {len(texts)} sentences; {args.out}/multi.json: {len(multi)}")


if __name__ == "__main__":
    main()
