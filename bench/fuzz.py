"""Fuzz fretc with mutated FRETish sentences.

    nice python bench/fuzz.py --count 100000 --seed 1 [--batch 40] [--audit-every 200]

Seeds are the sentences of ``shared/fretish/*.jsonl`` (FRET's vectors and trace cases) and the
198 NASA case-study requirements (``shared/corpora/fret_casestudies.jsonl``). Each input is a
seed with 1-4 mutations (token deletion, duplication, swap, replacement or insertion from a
vocabulary of FRETish words, operators and edge-case literals; splices of two sentences;
long operator chains; deep nesting; character edits). Every input goes through

1. parse and formalize, in-process (a ``FretishError`` is an accepted rejection);
2. monitor code generation (``compiler.codegen``), ``--batch`` accepted requirements per
   module, each module checked by ``codegen.check_module``;
3. the modules loaded and stepped over 30 random ticks in a child ``python -I -S`` (many
   modules per child), with the monitor protocol checked (``step`` returns a bool,
   ``status`` in satisfied/violated/unknown, ``finish`` equals the last verdict);
4. for one accepted requirement in ``--audit-every``, ``fretc audit`` (in-process, through
   the CLI) of a random CSV trace of its variables: exit 0, 1, 2 or 3, no traceback.

A failure is a traceback anywhere, an input that takes more than ``--slow`` seconds (CPU) in
steps 1-2 or its share of 3, or an invalid module. Failures are printed with their input and
written to ``--out`` (JSON lines); the exit status is 1 when there is any. Deterministic for a
given ``--seed``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SHARED = ROOT.parent / "shared"

# ------------------------------------------------------------------------ seeds and mutation
WORDS = """in during when if while except unless only after before mode upon whenever where
the shall always never eventually immediately initially finally within for until next at
first last timepoint same satisfy is true false TRUE FALSE ticks tick seconds second ms
milliseconds hours minute microseconds not and or of with probability occurrence previous
then xor mod abs""".split()
OPS = ["&", "|", "!", "~", "->", "=>", "<->", "<=>", "xor", "=", "!=", "<", "<=", ">", ">=",
       "+", "-", "*", "/", "^", "mod", "(", ")", ",", ".", "==", "&&"]
LITERALS = ["0", "1", "-1", "3.5", "1e999", "-1e999", "1e-400", "0.0", "007", "1" + "0" * 30,
            "1" + "0" * 99, "1" + "0" * 150, "9" * 4400, "15000", "999999", "1000001",
            "2.5", "-0", "1e308", "nan", "inf"]
NAMES = ["p", "q", "x", "y", "mode_a", "T", "X", "F", "G", "what", '"wind speed"', '"a\\"b"',
         '""', "é", "v" * 300, "__class__", "sys", "import", "self", "None", "math", "sample",
         "tick", "verdict", "first", "s0", "v0", "n1", "b_v0", "_div", "cpu%", "a.b"]
FUNCS = ["persisted", "occurred", "persists", "occurs", "preBool", "prevOcc", "nextOcc",
         "absReal", "absInt", "minReal", "maxInt", "preInt", "preReal", "foo"]
CHARS = list("()!&|^~-+*/=<>,.;:\"'#%$@`\\{}[]?") + ["\t", "\n", "\x00", "\u202e", "\x1b",
                                                    "é", "\u00a0", "𝔵", "Ω"]
TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[A-Za-z_][A-Za-z0-9_%.]*|[0-9][0-9.eE+-]*|<->|<=>|->|=>|'
                   r'<=|>=|!=|==|&&|\S')


def load_seeds() -> list:
    """Sentences of the shared FRETish vectors and the case-study corpus, deduplicated."""
    out = []
    for path in sorted((SHARED / "fretish").glob("*.jsonl")) + [
            SHARED / "corpora" / "fret_casestudies.jsonl"]:
        for line in path.read_text(encoding="utf-8").splitlines():
            row = json.loads(line)
            if "text" in row:
                out.append(row["text"])
            for case in row.get("cases", ()):
                out.append(case["sentence"])
    return list(dict.fromkeys(" ".join(t.split()) for t in out if t.strip()))


def _random_token(rng: random.Random) -> str:
    kind = rng.random()
    if kind < 0.3:
        return rng.choice(WORDS)
    if kind < 0.55:
        return rng.choice(OPS)
    if kind < 0.7:
        return rng.choice(LITERALS)
    if kind < 0.9:
        return rng.choice(NAMES)
    return rng.choice(FUNCS) + "("


def mutate(rng: random.Random, text: str, seeds: list) -> str:
    """``text`` with 1-4 random mutations (see the module docstring)."""
    toks = TOKEN.findall(text) or ["p"]
    for _ in range(rng.choice((1, 1, 1, 1, 1, 2, 2, 3, 4))):
        names = [k for k, t in enumerate(toks) if re.fullmatch(r"[a-z_][A-Za-z0-9_]*", t)
                 and t.lower() not in WORDS]
        op = rng.randrange(16)
        i = rng.randrange(len(toks)) if toks else 0
        if op in (7, 13, 14, 15) and names:
            i = rng.choice(names)  # operations that keep the sentence FRETish, mostly
        if op == 14:
            toks[i] = rng.choice(NAMES[:5] + NAMES[13:] + [f"w{rng.randrange(40)}"])
            continue
        if op == 15:
            toks[i:i + 1] = ["("] + [toks[i], rng.choice(["&", "|", "xor", "->", "<->"]),
                                     rng.choice(NAMES[:5])] + [")"]
            continue
        if op == 13:
            toks[i:i + 1] = ["("] + [toks[i], rng.choice(["<", ">", "=", "<=", "!="]),
                                     rng.choice(LITERALS)] + [")"]
            continue
        if op == 0 and len(toks) > 1:
            del toks[i]
        elif op == 1:
            toks.insert(i, toks[i] if toks else "p")
        elif op == 2 and len(toks) > 1:
            j = rng.randrange(len(toks))
            toks[i], toks[j] = toks[j], toks[i]
        elif op == 3:
            toks[i:i + 1] = [_random_token(rng)]
        elif op == 4:
            toks.insert(i, _random_token(rng))
        elif op == 5:  # splice with another sentence
            other = TOKEN.findall(rng.choice(seeds))
            toks = toks[:i] + other[rng.randrange(len(other) or 1):]
        elif op == 6:  # a long operator chain at the end
            n = rng.choice([5, 12, 50, 199, 200, 400, 1000])
            o = rng.choice(["&", "|", "xor", "->", "<->", "+", "*", "^"])
            names = [f"p{k % rng.choice([1, 3, 12, 100, 400])}" for k in range(n)]
            toks += [o] + " ".join(f"{a} {o}" for a in names).split()[:-1]
        elif op == 7:  # deep nesting at a token
            n = rng.choice([3, 50, 199, 200, 201, 500, 990])
            kind = rng.choice(["!", "(", "-", "abs", "pre"])
            pre, post = {"!": ("!" * n, ""), "(": ("(" * n, ")" * n), "-": ("- " * n, ""),
                         "abs": ("absReal(" * n, ")" * n),
                         "pre": ("preBool(false, " * (n // 4), ")" * (n // 4))}[kind]
            toks[i:i + 1] = [pre + (toks[i] if toks else "p") + post]
        elif op == 8:  # character edit
            s = " ".join(toks)
            k = rng.randrange(len(s) + 1)
            if rng.random() < 0.5:
                s = s[:k] + rng.choice(CHARS) + s[k:]
            else:
                s = s[:k] + s[k + 1:]
            toks = TOKEN.findall(s) if rng.random() < 0.5 else [s]
        elif op == 9:  # a number where a number goes
            nums = [k for k, t in enumerate(toks) if t[:1].isdigit()]
            if nums:
                toks[rng.choice(nums)] = rng.choice(LITERALS)
        elif op == 10:  # many variables
            n = rng.choice([11, 12, 30])
            toks += [rng.choice(["&", "|", "xor"])] + " & ".join(
                f"w{k}" for k in range(n)).split()
        elif op == 11:  # timing / scope swap
            toks[i:i + 1] = rng.choice([["within", rng.choice(LITERALS), "ticks"],
                                        ["for", "15000", "ticks"], ["after", "3", "seconds"],
                                        ["in", "m", "mode"], ["upon", "q"], ["until", "q"],
                                        ["before", "q"], ["only", "after", "m"],
                                        ["if", "p", "then"]])
        else:
            toks.insert(i, rng.choice(FUNCS) + "(" + rng.choice(LITERALS) + ", p)")
    return " ".join(toks)


def inputs(count: int, seed: int):
    """``count`` distinct mutated sentences, deterministic for ``seed``."""
    seeds = load_seeds()
    rng = random.Random(seed)
    seen = set()
    tries = 0
    while len(seen) < count and tries < count * 20:
        tries += 1
        t = mutate(rng, rng.choice(seeds), seeds)
        if t not in seen:
            seen.add(t)
            yield t


# ------------------------------------------------------------------------ in-process steps
class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def front(text: str, rid: str, source: str = "fuzz.fret"):
    """Parse and formalize ``text``; ``(compiled or None, rejected error or None)``."""
    from fretc.compiler.build import compile_entry
    from fretc.common.errors import FretishError
    from fretc.fretish.files import RequirementEntry
    from fretc.fretish.parser import parse

    try:
        req = parse(text, source=source, line=1, column=1)
        entry = RequirementEntry(id=rid, text=text, source=source, line=1, column=1,
                                 requirement=req)
    except FretishError as exc:
        return None, exc
    c = compile_entry(entry)
    if c.error is not None:
        return None, c.error
    if c.formalization is None:
        return None, "free-form"
    return c, None


# The child: load modules and step every monitor 30 ticks; one JSON line per module.
CHILD = r"""
import json, random, sys, traceback
for path in sys.argv[1:]:
    out = {"module": path, "errors": [], "monitors": 0}
    try:
        ns = {}
        exec(compile(open(path, encoding="utf-8").read(), path, "exec"), ns)
        rng = random.Random(path)
        for rid, cls in ns["MONITORS"].items():
            try:
                m = cls()
                last = None
                for t in range(30):
                    sample = {v: rng.choice((True, False, 0, 1, 2.5, -3, 1e300))
                              for v in cls.VARIABLES}
                    last = m.step(sample)
                    if type(last) is not bool:
                        raise TypeError(f"step returned {type(last).__name__}")
                    if m.status not in ("satisfied", "violated", "unknown"):
                        raise ValueError(f"status {m.status!r}")
                if m.finish() != last:
                    raise ValueError("finish() differs from the last step")
                m.reset()
                out["monitors"] += 1
            except Exception:
                out["errors"].append([rid, traceback.format_exc()[-1500:]])
    except BaseException:
        out["errors"].append(["<module>", traceback.format_exc()[-1500:]])
    print(json.dumps(out), flush=True)
"""


def run_children(paths, timeout: float):
    """Load and step the modules ``paths`` in one ``python -I -S`` child."""
    t0 = time.time()
    proc = subprocess.run([sys.executable, "-I", "-S", "-c", CHILD] + [str(p) for p in paths],
                          capture_output=True, text=True, timeout=timeout)
    results = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    if proc.returncode != 0 or len(results) != len(paths):
        results.append({"module": "<child>", "monitors": 0,
                        "errors": [["<child>", proc.stderr[-1500:]]]})
    return results, time.time() - t0


def audit_csv(c, workdir: Path, rng: random.Random):
    """``fretc audit`` of a random CSV of the requirement's variables; the exit code."""
    from click.testing import CliRunner

    from fretc.cli import main

    fret = workdir / "a.fret"
    fret.write_text(f"A: {c.text}\n", encoding="utf-8")
    names = list(c.formalization.variables)
    with open(workdir / "a.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for _ in range(rng.randint(1, 40)):
            w.writerow([rng.choice(["0", "1", "2.5", "-1", "0"]) for _ in names])
    res = CliRunner().invoke(main, ["audit", "-r", str(fret), str(workdir / "a.csv"),
                                    "--no-progress"])
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        raise res.exception
    return res.exit_code


# ------------------------------------------------------------------------ main
def _arguments(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--batch", type=int, default=40, help="requirements per module")
    ap.add_argument("--modules-per-child", type=int, default=25)
    ap.add_argument("--audit-every", type=int, default=200)
    ap.add_argument("--slow", type=float, default=5.0, help="seconds (CPU) per input")
    ap.add_argument("--out", default="fuzz_failures.jsonl")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--minutes", type=float, default=None,
                    help="stop after this many minutes (wall clock) and report what ran")
    ap.add_argument("--shard", default="0/1", help="K/N: run the inputs whose index is K mod N "
                    "(N processes with the same --seed run distinct inputs)")
    return ap.parse_args(argv)


class _Fuzzer:
    """One fuzzing run: the statistics, the failures, the batch of monitors waiting to be
    rendered into a module and the modules waiting to be stepped in a child."""

    def __init__(self, args):
        from fretc.compiler import codegen  # after sys.path has the repository

        self.codegen = codegen
        self.args = args
        self.stats = {"inputs": 0, "rejected": 0, "accepted": 0, "monitors": 0, "modules": 0,
                      "skipped": 0, "audited": 0, "tracebacks": 0, "slow": 0,
                      "invalid_modules": 0, "max_input_s": 0.0}
        self.failures: list = []
        self.rng = random.Random(args.seed + 1)
        self.tmp = Path(tempfile.mkdtemp(prefix="fretc_fuzz_"))
        self.pending_modules: list = []
        self.batch: list = []  # (MonitorSource, text)
        self.texts_of_module: dict = {}
        self.cpu0, self.wall0 = time.process_time(), time.time()

    def fail(self, kind, text, detail):
        self.stats[kind] += 1
        self.failures.append({"kind": kind, "input": text, "detail": detail})
        if not self.args.quiet:
            print(f"FAIL {kind}: {text[:300]!r}\n  {detail[-600:]}", flush=True)

    def flush_children(self, force=False):
        """Step the pending modules in a child ``python -I -S`` (see :func:`run_children`)."""
        pending, args = self.pending_modules, self.args
        if not pending or (len(pending) < args.modules_per_child and not force):
            return
        paths = list(pending)
        pending.clear()
        try:
            results, took = run_children(paths, timeout=600)
        except subprocess.TimeoutExpired:
            for p in paths:
                self.fail("slow", "\n".join(self.texts_of_module[str(p)]), "child timed out")
            return
        n = sum(len(self.texts_of_module[str(p)]) for p in paths)
        if took / max(n, 1) > args.slow:
            self.fail("slow", "", f"stepping took {took:.1f} s for {n} monitors")
        for r in results:
            self.stats["monitors"] += r["monitors"]
            for rid, tb in r["errors"]:
                self.stats["invalid_modules"] += 1
                self.failures.append({"kind": "invalid_modules", "module": r["module"],
                                      "input": rid, "detail": tb,
                                      "inputs": self.texts_of_module.get(r["module"], [])})
                if not args.quiet:
                    print(f"FAIL invalid module {r['module']} {rid}: {tb[-600:]}", flush=True)
        for p in paths:
            os.unlink(p)
            self.texts_of_module.pop(str(p), None)

    def flush_batch(self, force=False):
        """Render the batch into one module, check it and queue it for a child."""
        batch, codegen = self.batch, self.codegen
        if not batch or (len(batch) < self.args.batch and not force):
            return
        name = f"m{self.stats['modules']}"
        self.stats["modules"] += 1
        sources = [m for m, _ in batch]
        texts = [t for _, t in batch]
        batch.clear()
        signal.setitimer(signal.ITIMER_PROF, self.args.slow * len(sources))
        signal.signal(signal.SIGPROF, _alarm)
        try:
            text = codegen._render(sources, [], name)
            codegen.check_module(text, name)
        except codegen.InvalidMonitorError as exc:
            self.fail("invalid_modules", "\n".join(texts), str(exc))
            return
        except _Timeout:
            self.fail("slow", "\n".join(texts), "module render/check over the limit")
            return
        except Exception:
            self.fail("tracebacks", "\n".join(texts), traceback.format_exc())
            return
        finally:
            signal.setitimer(signal.ITIMER_PROF, 0)
        path = self.tmp / f"{name}.py"
        path.write_text(text, encoding="utf-8")
        self.pending_modules.append(path)
        self.texts_of_module[str(path)] = texts
        self.flush_children(force)

    def front_end(self, k: int, text: str):
        """Parse, formalize and build the monitor of input ``k`` under the CPU limit:
        (compiled requirement or None, MonitorSource or None), or None after a failure."""
        signal.setitimer(signal.ITIMER_PROF, self.args.slow)
        try:
            c, _rejected = front(text, f"F{k}")
            ms = None
            if c is not None:
                try:
                    ms = self.codegen.monitor_source(c, len(self.batch))
                except self.codegen.CodegenError:
                    self.stats["skipped"] += 1
            return c, ms
        except _Timeout:
            self.fail("slow", text, f"over {self.args.slow} s in parse/formalize/codegen")
        except RecursionError:
            self.fail("tracebacks", text, traceback.format_exc()[-1500:])
        except Exception:
            self.fail("tracebacks", text, traceback.format_exc())
        finally:
            signal.setitimer(signal.ITIMER_PROF, 0)
        return None

    def one_input(self, k: int, text: str) -> None:
        t0 = time.process_time()
        got = self.front_end(k, text)
        if got is None:
            return
        c, ms = got
        self.stats["max_input_s"] = max(self.stats["max_input_s"], time.process_time() - t0)
        if c is None:
            self.stats["rejected"] += 1
            return
        self.stats["accepted"] += 1
        if ms is not None:
            self.batch.append((ms, text))
        if self.stats["accepted"] % self.args.audit_every == 1:
            self.stats["audited"] += 1
            try:
                code = audit_csv(c, self.tmp, self.rng)
                if code not in (0, 1, 2, 3):
                    self.fail("tracebacks", text, f"audit exit {code}")
            except Exception:
                self.fail("tracebacks", text, "audit: " + traceback.format_exc())

    def run(self) -> int:
        args, stats = self.args, self.stats
        signal.signal(signal.SIGPROF, _alarm)
        shard, shards = (int(x) for x in args.shard.split("/"))
        current = open(args.out + ".current", "w", encoding="utf-8")
        for k, text in enumerate(inputs(args.count * shards, args.seed)):
            if k % shards != shard:
                continue
            if stats["inputs"] >= args.count or (
                    args.minutes is not None and time.time() - self.wall0 > args.minutes * 60):
                break
            stats["inputs"] += 1
            if k % 16 == 0 or len(text) > 200:  # for a hang inside C code (Spot), which no
                current.seek(0)                  # signal interrupts: the input is on disk
                current.truncate()
                current.write(text)
                current.flush()
            self.one_input(k, text)
            self.flush_batch()
            if not args.quiet and stats["inputs"] % 1000 == 0:
                print(json.dumps(stats), f"cpu {time.process_time() - self.cpu0:.0f} s "
                      f"wall {time.time() - self.wall0:.0f} s", flush=True)
        self.flush_batch(force=True)
        self.flush_children(force=True)
        stats["cpu_s"] = round(time.process_time() - self.cpu0, 1)
        stats["wall_s"] = round(time.time() - self.wall0, 1)
        stats["max_input_s"] = round(stats["max_input_s"], 3)
        with open(args.out, "w", encoding="utf-8") as fh:
            for f in self.failures:
                fh.write(json.dumps(f) + "\n")
        print(json.dumps(stats))
        return 1 if self.failures else 0


def main(argv=None) -> int:
    args = _arguments(argv)
    signal.signal(signal.SIGALRM, _alarm)
    return _Fuzzer(args).run()


if __name__ == "__main__":
    sys.exit(main())
