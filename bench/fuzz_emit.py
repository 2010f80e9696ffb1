"""The ``crunner``, ``split``, ``prism``, ``entities`` and ``windows`` classes of
``bench/fuzz_hostile.py`` (its docstring): the C monitors' runner and their naming, PRISM
properties, the per-entity bound, and windows over 10^6 messages.

* ``crunner``: a CSV trace of random rows for the C runner of five requirements (built once
  per process with ``-std=c99 -pedantic -Werror`` and the sanitizers), half of them sampled
  traces of plain and per-entity clocks as ``--write-csv`` writes them, with hostile bytes at
  random places: NUL, bytes that are not UTF-8, CR, quotes, tabs, empty lines, comment
  lines, long cells, numbers that overflow. Oracle: the runner never stops at a byte and
  reports the rows before it: where ``fretc audit`` refuses the file the runner exits 2
  naming ``FILE:LINE``; where the audit reads it, each word the runner gives is the audit's
  (a tick a NaN leaves unread: ``unknown``, as tests/audit/test_sampled_csv.py); no
  sanitizer report.
* ``split``: 2-4 requirement files whose stems and ids collide once joined (``a`` + ``b_c``
  and ``a_b`` + ``c``, names differing in case, ids of 40+ characters, suffixes the C names
  use), emitted with and without ``--split``. Oracle: no two files share a name whatever
  the case, every ``#include`` of the runner exists, the folder builds pedantic, and the
  runner on a random trace gives each requirement once, with the audit's word.
* ``prism``: a random requirement with probability bounds (edge values: ``< 1e-400``,
  ``> 0.99999999999999999999``) and FRETish functions (abs, min, max, the past-time ones,
  an uninterpreted one). Oracle: every property written parses by PRISM's property grammar
  as far as names go (only PRISM's operators and built-in functions, no past-time operator),
  a refused requirement is named on stderr, a bound 0 or 1 as a double is never written.
* ``entities``: a ``/tracks`` log of 3-9 tracks with the entity bound set to 2-6 and at
  most one track violating the requirement. Oracle: the requirement is violated exactly when
  a judged track violates it; else an error exactly when tracks were left unjudged; the
  unjudged ones never under the requirement's own name.
* ``windows``: 10^6 messages at 1 kHz of a ramp ``x = k``, ``median``/``percentile`` over
  900 s, against ``max`` over the same log. Oracle: the first violation at the tick the
  ramp gives analytically, and the median's CPU time under 5 times the max's (the ratio is
  printed: the order-statistics structure's cost in one run).
"""

from __future__ import annotations

import random
import re
import struct
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

RUNNER_REQS = ("@tick_period 1 s\n"
               "A1: whenever p the sw shall within 2 ticks satisfy x > 1\n"
               "A2: in m the sw shall always satisfy y\n"
               "A3: upon q the sw shall eventually satisfy x / y >= 0.5\n"
               "A4: only after p the sw shall never satisfy x <= 0\n"
               "A5: the sw shall always satisfy y | persisted(2, p)\n")
HOSTILE_BYTES = [b"\x00", b"\xff", b"\xc3(", b"\r", b"\r\n", b'"', b"\t", b"\n\n", b"# c\n",
                 b"1e999", b"-1e999", b"nan", b"x" * 5000, b",", b"\xef\xbb\xbf"]
_CACHE: dict = {}


def _cli(args: list[str]):
    from click.testing import CliRunner

    from fretc.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


def _build(folder: Path, name: str) -> tuple[Path | None, str]:
    """The runner of ``folder`` built pedantic with the sanitizers; (None, why) on failure."""
    from _c_monitors import SANITIZE, STRICT, c_compiler

    cc = c_compiler()
    if cc is None:
        return None, "no C compiler"
    srcs = sorted(p.name for p in folder.glob("*.c"))
    got = subprocess.run([cc, *STRICT, *SANITIZE, "-o", name, *srcs, "-lm"], cwd=folder,
                         capture_output=True, text=True)
    if got.returncode != 0 or got.stderr.strip():
        return None, got.stderr[-1500:]
    return folder / name, ""


def _audit_words(fret: Path, trace: Path) -> tuple[dict | None, str | None]:
    """({id: verdict} of ``fretc audit`` of ``trace``, or None and the error)."""
    from fretc.audit import AuditConfig, audit_log, load_plan

    la = audit_log(load_plan(AuditConfig(requirements=(str(fret),))), str(trace))
    _AUDIT_ERRORS[:] = [v.error for v in la.verdicts if v.error]
    if la.error is not None:
        return None, la.error
    return {v.requirement: v.verdict for v in la.verdicts}, None


#: the error verdicts of the last :func:`_audit_words` (a sampled trace's clocks are read
#: apart: one clock's bad row is its requirements' error, the others judged)
_AUDIT_ERRORS: list[str] = []


def _runner_words(exe: Path, trace: Path) -> tuple[int, dict, str]:
    """(exit status, {id: word}, stderr) of the runner on ``trace``: ids as the audit gives
    them (the runner prints a backslash or a control byte as ``\\xNN``); a word ``unknown``
    at an unread tick is ``unread``, and so is a per-entity requirement's ``unknown`` when
    one of its entities is unread (the runner stops where the audit judges on)."""
    from fretc.logs.csv.source import unescape_id

    got = subprocess.run([str(exe), str(trace)], capture_output=True, timeout=60)
    words, unread = {}, set()
    for line in got.stdout.decode("utf-8", "replace").splitlines():
        cells = line.split("\t")
        if len(cells) >= 2:
            rid = unescape_id(cells[0])
            words[rid] = cells[1]
            if any(c.startswith("unread=") for c in cells):
                unread.add(rid)
                unread.add(rid.split("[", 1)[0])
    return got.returncode, {k: ("unread" if k in unread and v == "unknown" else v)
                            for k, v in words.items()}, got.stderr.decode("utf-8", "replace")


def run_crunner(rng: random.Random, tmp: Path) -> list[str]:
    """One hostile trace for the C runner (module docstring)."""
    if "crunner" not in _CACHE:
        d = tmp / "crunner"
        d.mkdir(exist_ok=True)
        (d / "r.fret").write_text(RUNNER_REQS)
        res = _cli([d / "r.fret", "--emit", "c", "-o", d / "c"])
        if res.exit_code != 0:
            return [f"--emit c failed: {res.output[-500:]}"]
        exe, why = _build(d / "c", "runner")
        if exe is None:
            return [f"the runner does not build: {why}"]
        _CACHE["crunner"] = (d / "r.fret", exe)
    fret, exe = _CACHE["crunner"]
    cell = lambda: rng.choice(["true", "false", "0", "1", "2", "-1", "0.5", "nan", "inf"])  # noqa: E731
    if rng.random() < 0.5:
        data = _sampled_trace(rng, cell)
    else:
        rows = [",".join(cell() for _ in range(5)).encode() for _ in range(rng.randrange(0, 15))]
        data = bytearray(b"m,p,q,x,y\n" + b"\n".join(rows) + b"\n")
    for _ in range(rng.randrange(0, 3)):
        at = rng.randrange(len(data) + 1)
        data[at:at] = rng.choice(HOSTILE_BYTES)
    trace = tmp / f"t{rng.randrange(10**9)}.csv"
    trace.write_bytes(bytes(data))
    audit, error = _audit_words(fret, trace)
    code, words, err = _runner_words(exe, trace)
    trace.unlink()
    if "Sanitizer" in err or "runtime error" in err:
        return [f"sanitizer: {err[-800:]}"]
    if audit is None:
        if code != 2 or not re.search(rf"{re.escape(str(trace))}:\d+", err):
            return [f"the audit refuses it ({error[:200]}) but the runner exits {code}: "
                    f"{err[-300:]!r} {words}"]
        return []
    bad = [f"{rid}: runner {w}, audit {audit.get(rid)}" for rid, w in words.items()
           if w != "unread" and w != audit.get(rid)]
    if code == 2 and "a NUL byte: not a text trace" in err and \
            re.search(rf"{re.escape(str(trace))}:\d+", err) and not words:
        return []  # a NUL anywhere, a comment line's too: the documented refusal, its line
    if code == 2 and "quoted cells are not read by this runner" in err and \
            re.search(rf"{re.escape(str(trace))}:\d+", err) and not words:
        return []  # a documented refusal with its line (docs/guide/robot-monitors.md)
    named = re.search(rf"{re.escape(str(trace))}:\d+(?!\d)", err)
    if code == 2 and named and not words and any(
            re.search(rf"{re.escape(named.group(0))}(?!\d)", e) for e in _AUDIT_ERRORS):
        return []  # a clock's row the audit refuses too: the runner refuses the whole file
    if code == 2 and "error:" in err and not words:
        return [f"the runner refuses what the audit reads: {err[-300:]!r}"]
    return bad


def _sampled_trace(rng: random.Random, cell) -> bytearray:
    """A trace as ``--write-csv`` writes it, of plain and per-entity clocks: A1 and A4 on
    one clock, A2 and A5 per entity ``e`` (names with a space, a comma, a backslash, bytes
    over 127, escaped as the writer escapes them; some entities on a not-sampled line), A3 on
    no clock; each row of a random clock, time rising."""
    from fretc.logs.csv.source import escape_id

    lines = ["# fretc sampled trace of fuzz.mcap: the FRET variables", "# fretc clock 1: A1 A4"]
    k = 1
    for rid in ("A2", "A5"):
        lines.append(f"# fretc per entity: {rid}: e")
        for name in rng.sample(["a", "b c", "d,e", "f\\g", "h\u00e9", "7"], rng.randrange(0, 5)):
            if rng.random() < 0.2:
                lines.append(f"# fretc not sampled: {escape_id(f'{rid}[e={name}]')}: no tick")
            else:
                k += 1
                lines.append(f"# fretc clock {k}: {escape_id(f'{rid}[e={name}]')}")
    lines.append("time,tick,m,p,q,x,y")
    for i in range(rng.randrange(0, 25)):
        lines.append(f"{i / 10},{rng.randrange(1, k + 1)}," + ",".join(cell() for _ in range(5)))
    return bytearray(("\n".join(lines) + "\n").encode())


def _split_files(rng: random.Random) -> dict[str, list[str]]:
    """2-4 requirement files (relative path -> ids) whose names collide once joined."""
    long_id = "R" + "x" * rng.randrange(40, 90)
    pool = [{"a.fret": ["b_c"], "a_b.fret": ["c"]},
            {"one/Safe.fret": ["R"], "two/safe.fret": ["r"]},
            {"x.fret": ["A", "B"], "x_A.fret": ["h"], "x_a.fret": ["step"]},
            {"m.fret": [long_id, long_id + "y"], "m_" + long_id[:30] + ".fret": ["z"]},
            {"runner.fret": ["c"], "s.fret": ["monitors", "init", "ID"]}]
    files: dict[str, list[str]] = {}
    for choice in rng.sample(pool, rng.randrange(1, 3)):
        for name, ids in choice.items():
            files.setdefault(name, [])
            files[name] += [i for i in ids if all(i not in v for v in files.values())]
    return {k: v for k, v in files.items() if v}


def run_split(rng: random.Random, tmp: Path) -> list[str]:
    """One emission of colliding names, split or not (module docstring)."""
    d = tmp / f"split{rng.randrange(10**9)}"
    files = _split_files(rng)
    names, paths = [], []
    for k, (name, ids) in enumerate(files.items()):
        p = d / "in" / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text("".join(f"{i}: the sw shall always satisfy v{k}_{j}\n"
                             for j, i in enumerate(ids)))
        paths.append(p)
        names += [(i, f"v{k}_{j}") for j, i in enumerate(ids)]
    split = rng.random() < 0.5
    res = _cli([*paths, "--emit", "c", "-o", d / "c", *(["--split"] if split else [])])
    if res.exit_code != 0:
        return [f"--emit c{' --split' * split} exit {res.exit_code}: {res.output[-400:]}"]
    out = sorted(p.name for p in (d / "c").iterdir())
    bad = []
    if len({n.lower() for n in out}) != len(out):
        bad.append(f"file names differ only in case: {out}")
    incs = re.findall(r'#include "([^"]+)"', (d / "c" / "runner.c").read_text())
    if len(incs) != len(set(incs)) or not all((d / "c" / i).exists() for i in incs):
        bad.append(f"the runner's includes: {incs}")
    exe, why = _build(d / "c", "runner")
    if exe is None:
        return bad + [f"does not build: {why[-600:]}"]
    values = {v: rng.random() < 0.5 for _i, v in names}
    trace = d / "t.csv"
    trace.write_text(",".join(values) + "\n" + ",".join(str(x).lower() for x in values.values())
                     + "\n")
    _code, words, _err = _runner_words(exe, trace)
    want = {i: "satisfied" if values[v] else "violated" for i, v in names}
    if words != want:
        bad.append(f"runner words {words} != {want}")
    return bad


_PRISM_WORDS = {"P", "F", "G", "X", "U", "R", "W", "true", "false", "min", "max", "pow", "mod",
                "floor", "ceil", "round", "log"}
_FUNCS = ["absReal(x) > 1", "absInt(x) < 3", "minReal(x, y) > 0", "maxInt(x, y) <= 2",
          "persisted(2, p)", "occurred(3, p)", "preBool(false, p)", "preInt(0, x) > 1",
          "det(x, y) > 0", "x + y > 1", "p", "!p & x > 0"]
_BOUNDS = ["< 1e-400", "<= 1e-400", "> 0.99999999999999999999", ">= 0.9", "< 0.5", "= 0.5",
           "!= 1", "> 0", "< 1", ">= 1e-300"]


def run_prism(rng: random.Random, tmp: Path) -> list[str]:
    """One requirement set emitted as PRISM properties (module docstring)."""
    d = tmp / f"prism{rng.randrange(10**9)}"
    d.mkdir(parents=True)
    lines = []
    for k in range(rng.randrange(1, 4)):
        resp = " | ".join(rng.sample(_FUNCS, rng.randrange(1, 3)))
        lines.append(f"P{k}: {rng.choice(['', 'upon p '])}the sw shall with probability "
                     f"{rng.choice(_BOUNDS)} {rng.choice(['always', 'eventually'])} satisfy "
                     f"{resp}")
    (d / "p.fret").write_text("\n".join(lines) + "\n")
    res = _cli([d / "p.fret", "--emit", "prism", "-o", d / "p.props"])
    if "Traceback" in res.output or res.exception and not isinstance(res.exception,
                                                                       SystemExit):
        return [f"internal error: {res.output[-400:]}"]
    if not (d / "p.props").exists():
        return []  # every requirement refused by the parser: an error already
    bad = []
    for line in (d / "p.props").read_text().splitlines():
        if line.startswith("//"):
            continue
        body = line.split(":", 1)[1]
        for word in re.findall(r"[A-Za-z_][A-Za-z0-9_]*(?=\s*\()", body):
            if word not in _PRISM_WORDS:
                bad.append(f"{word}(...) written: {line}")
        for op, num in re.findall(r"P(<=|>=|<|>)([0-9.eE+-]+) \[", body):
            if (op == "<" and float(num) == 0) or (op == ">" and float(num) == 1):
                bad.append(f"a bound no probability meets written: {line}")
    refused = (d / "p.props").read_text().count("//   not in PRISM: ")
    if refused != res.output.count("skipped "):
        bad.append(f"{refused} refused in the file, {res.output.count('skipped ')} on stderr")
    return bad


TRACK_BINDINGS = ('[tick]\nperiod = "100 ms"\n[entities]\ntrack = "/tracks.tracks[:].id"\n'
                  "[variables]\ndist = 'min(/tracks.tracks[:]{id==$track}.distance)'\n"
                  "present = 'count(/tracks.tracks[:]{id==$track}.distance >= 0) = 1'\n")


def run_entities(rng: random.Random, tmp: Path) -> list[str]:
    """One log of tracks past a random entity bound (module docstring)."""
    from _logs import S, write_mcap
    from fretc.audit import AuditConfig, audit_log, load_plan

    sys.path.insert(0, str(ROOT / "tests" / "audit"))
    from test_entities import _track_types

    Track, TrackArray = _track_types()
    d = tmp / f"ent{rng.randrange(10**9)}"
    d.mkdir(parents=True)
    n, bound = rng.randrange(3, 10), rng.randrange(2, 7)
    bad_track = rng.choice([None] + list(range(1, n + 1)))
    msgs = [("/tracks", "tracking_msgs/msg/TrackArray", S + k * S // 10, TrackArray(
        tracks=[Track(id=i, distance=0.2 if i == bad_track and k == 3 else 2.0)
                for i in range(1, n + 1)])) for k in range(6)]
    (d / "t.fret").write_text("@tick_period 100 ms\n"
                              "T: in present mode the robot shall always satisfy dist > 0.5\n")
    (d / "t.bindings.toml").write_text(TRACK_BINDINGS)
    # (the audit's bound is --max-entities; E.MAX_ENTITIES is the watch's)
    got = audit_log(load_plan(AuditConfig(requirements=(str(d / "t.fret"),),
                                          max_entities=bound)),
                    str(write_mcap(d / "t.mcap", msgs))).verdicts
    names = [v.requirement for v in got]
    judged = [v for v in got if re.fullmatch(r"T\[track=\d+\]", v.requirement)]
    whole = [v for v in got if v.requirement == "T"]
    bad = [] if len(whole) == 1 else [f"{len(whole)} verdicts named T: {names}"]
    violated = any(v.verdict == "violated" for v in judged)
    want = "violated" if violated else "error" if n > bound else "satisfied"
    if whole and whole[0].verdict != want:
        bad.append(f"T {whole[0].verdict}, want {want} ({n} tracks, bound {bound}, "
                   f"track {bad_track} bad)")
    return bad


def _ramp_log(path: Path, n: int) -> Path:
    """``/x`` Float64 ``k`` at ``k`` ms, ``n`` messages (an MCAP written by hand)."""
    from mcap.writer import CompressionType, Writer

    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=CompressionType.LZ4)
        w.start("ros2", "fretc-fuzz")
        ch = w.register_channel("/x", "cdr", w.register_schema("std_msgs/msg/Float64",
                                                               "ros2msg", b"float64 data"))
        for k in range(n):
            w.add_message(ch, log_time=k * 1_000_000, publish_time=k * 1_000_000,
                          data=b"\x00\x01\x00\x00" + struct.pack("<d", float(k)))
        w.finish()
    return path


def run_windows(rng: random.Random, tmp: Path) -> list[str]:
    """10^6 messages: a median or percentile window against max (module docstring)."""
    from fretc.audit import AuditConfig, audit_log, load_plan

    n, span = 1_000_000, 900
    log = _CACHE.get("ramp") or _ramp_log(tmp / "ramp.mcap", n)
    _CACHE["ramp"] = log
    q = rng.choice([50, 90, 10])
    func = "median(/x.data, 900 s)" if q == 50 else f"percentile(/x.data, {q}, 900 s)"
    c = rng.randrange(460_000, 540_000)
    out = {}
    for name, expr in (("order", func), ("max", "max(/x.data, 900 s)")):
        d = tmp / f"w{name}{rng.randrange(10**9)}"
        d.mkdir()
        (d / "w.fret").write_text("@tick_period 1 s\nW: the sw shall always satisfy w < "
                                  f"{c}\n")
        (d / "w.bindings.toml").write_text(f'[tick]\nperiod = "1 s"\n[variables]\nw = "{expr}"\n')
        t0 = time.process_time()
        (v,) = audit_log(load_plan(AuditConfig(requirements=(str(d / "w.fret"),))),
                         str(log)).verdicts
        out[name] = (v, time.process_time() - t0)
    v, cpu = out["order"]
    # at tick t (ms) the window holds messages t-899999..t: the q-th percentile (linear
    # between ranks) of that run of consecutive values is t - 899999 + q/100 * 899999
    first = next((t for t in range(span * 1000, n, 1000)
                  if t - 899_999 + q / 100 * 899_999 >= c), None)  # None: never reached
    got = v.first_violation.at.time_ns if v.first_violation else None
    bad = []
    if (v.verdict, got) != (("violated", first * 1_000_000) if first is not None
                            else ("satisfied", None)):
        bad.append(f"{func} < {c}: {v.verdict} at {got}, want "
                   f"{None if first is None else first * 1_000_000}")
    ratio = cpu / max(out["max"][1], 1e-9)
    print(f"windows: {func} over {n:,} messages: {cpu:.2f} s CPU, max {out['max'][1]:.2f} s: "
          f"ratio {ratio:.2f}", flush=True)
    if ratio > 5:
        bad.append(f"{func}: {ratio:.1f} times the CPU of max over the same log")
    return bad


#: the classes of this module for bench/fuzz_hostile.py: name -> (runner, weight)
EMIT_CLASSES = {"crunner": (run_crunner, 4), "split": (run_split, 0.5),
                "prism": (run_prism, 4), "entities": (run_entities, 1),
                "windows": (run_windows, 0.02)}

__all__ = ["EMIT_CLASSES", "run_crunner", "run_split", "run_prism", "run_entities",
           "run_windows"]
