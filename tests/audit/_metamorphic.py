"""The inputs and relations of tests/audit/test_metamorphic.py: every log the tests have,
a requirement set for each (the shipped ones where they exist, else one generated from what
``fretc inspect`` lists of the log, with bindings using every function and modifier of the
binding language), and the audits compared.

Each relation compares the whole per-requirement JSON (:func:`verdicts`), not the verdict
alone; ``log`` (the path audited) and ``source`` (the file and line a requirement was read
from) are the only members left out, since the relation itself changes them.
"""

from __future__ import annotations

import json
import random
import zlib
from dataclasses import dataclass
from pathlib import Path

from fretc.audit import AuditConfig, audit_log, load_plan
from fretc.cli.inspect import inspect_log

from _shared import PRESENT, SHARED

ROOT = Path(__file__).resolve().parents[2]
DATA = SHARED / "data"
#: members of a verdict that name where it was read, not what it is
WHERE = ("log", "source")


@dataclass(frozen=True)
class Case:
    """One log and the requirement set audited on it: ``fret`` and ``bindings`` texts."""

    id: str
    log: Path
    fret: str
    bindings: str


# --------------------------------------------------------------------------- the logs
def shipped_cases() -> list[Case]:
    """The shipped runs with the shipped requirements."""
    fret = (ROOT / "requirements" / "safe_ros.fret").read_text()
    fret += (ROOT / "requirements" / "r1.fret").read_text()
    bindings = (ROOT / "requirements" / "safe_ros.bindings.toml").read_text()
    return [Case(f"traces/{p.name}", p, fret, bindings)
            for p in sorted((ROOT / "traces").glob("*.mcap"))]


def real_cases() -> list[Case]:
    """The two real logs of ../shared/data/logs with requirements/real_logs."""
    if not PRESENT:
        return []
    out = []
    for p in sorted((DATA / "logs").iterdir()):
        req = ROOT / "requirements" / "real_logs"
        out.append(Case(f"logs/{p.name}", p, (req / f"{p.stem}.fret").read_text(),
                        (req / f"{p.stem}.bindings.toml").read_text()))
    return out


def foreign_logs() -> list[Path]:
    """Every log of ../shared/data/foreign_logs (ROS 1 bags, MCAP, PX4 ULog)."""
    if not PRESENT:
        return []
    return sorted(p for p in (DATA / "foreign_logs").rglob("*")
                  if p.suffix in (".bag", ".mcap", ".ulg"))


def conformance_logs() -> list[Path]:
    """The MCAP conformance files of ../shared/data/mcap_conformance that hold messages."""
    if not PRESENT:
        return []
    return sorted(p for p in (DATA / "mcap_conformance").glob("TenMessages*.mcap"))


# --------------------------------------------------------------------------- generated sets
#: forms of a numeric field ``{p}`` (the field's path, its topic ``{t}``)
NUMBER_FORMS = ["{p}", "abs({p})", "{p}@abs", "{p}@negative", "{p}@delta", "{p}@derivative",
                "{p}@timedelta", "derivative({p})", "sqrt(abs({p}))", "{p}@rad2deg",
                "{p}@deg2rad", "delta({p})", "timedelta({p})", "{p}@sqrt",
                "max_of_messages({p})", "min_of_messages({p})", "age({t})",
                "min({p}, {p} + 1)", "max({p}, 0)",
                # trigonometry (radians), each defined on every double the sweep draws
                "sin({p}) + cos({p})", "atan({p}) - tan({p} * 1e-3)",
                "asin(sin({p})) + acos(cos({p}))", "atan2({p}, 1)",
                # windows over time (the whole binding): a duration, a count of messages
                "mean({p}, 500 ms)", "percentile({p}, 90, 1 s)", "sum({p}, 3 messages)",
                "variance({p}, 1 s)", "median({p}, 2 messages)", "rate({t}, 1 s)"]
#: aggregations over the messages between ticks: the whole binding, compared in the
#: requirement (a numeric variable) or a condition in itself
WHOLE = ("max_of_messages(", "min_of_messages(", "any_of_messages(", "all_of_messages(",
         "count_of_messages(", "mean(", "percentile(", "sum(", "variance(", "median(",
         "rate(")
#: forms of an array of numbers ``{p}`` (its items ``{p}[:]``)
ARRAY_FORMS = ["min({p}[:])", "max({p}[:])", "mean({p}[:])", "norm({p}[:])", "len({p})",
               "count({p}[:] > {c})", "invalid({p})"]
#: forms of a boolean field (already a condition)
BOOL_FORMS = ["{p}", "!{p}", "any_of_messages({p})", "all_of_messages({p})", "{p} == 1",
              "{p} != 0", "count_of_messages({p}) > 0", "unchanged({p})"]
#: requirement templates over the variables ``{a}`` and ``{b}``
TEMPLATES = ["the sys shall always satisfy {a}", "the sys shall never satisfy {a}",
             "upon {a} the sys shall within 3 ticks satisfy {b}",
             "whenever {a} the sys shall immediately satisfy {b}",
             "in {a} mode the sys shall always satisfy {b}",
             "the sys shall eventually satisfy {a}",
             "upon {a} the sys shall for 2 ticks satisfy {b}",
             "after {a} the sys shall always satisfy {b}"]


def _fields(doc: dict) -> tuple[list, list, list]:
    """(numeric fields with their range, arrays of numbers with their range, booleans) of
    an inspect document, each ``(path, topic)``."""
    nums, arrays, bools = [], [], []
    for t in doc["topics"]:
        topic = t["topic"] if t["topic"].startswith("/") else json.dumps(t["topic"])
        for path, f in t["fields"].items():
            if "[:]" in path or "[" in path.split(".")[-1]:
                continue
            if "min" in f and "lengths" in f and f["lengths"][1] > 0:
                arrays.append((path, topic, f["min"], f["max"]))
            elif "min" in f and "lengths" not in f:
                nums.append((path, topic, f["min"], f["max"]))
            elif "true" in f and "lengths" not in f:
                bools.append((path, topic))
    return nums, arrays, bools


def _threshold(rng: random.Random, lo: float, hi: float) -> str:
    """A threshold within the field's range (its values fall on both sides)."""
    x = lo + (hi - lo) * rng.choice([0.1, 0.5, 0.9]) if hi > lo else lo
    return repr(round(x, 6))


def generated_set(doc: dict, seed: int, n: int = 4) -> tuple[str, str] | None:
    """A requirement set of ``n`` requirements (and its bindings) for the log inspected in
    ``doc``, drawn with ``seed``: variables are comparisons of the fields' forms (every form
    of :data:`NUMBER_FORMS`, :data:`ARRAY_FORMS`, :data:`BOOL_FORMS` in turn, starting at
    ``seed``) with thresholds inside the ranges seen; None when the log has no field to
    bind."""
    rng = random.Random(seed)
    nums, arrays, bools = _fields(doc)
    if not (nums or arrays or bools):
        return None
    variables: dict[str, str] = {}
    conditions: list[str] = []  # what the requirement reads of each variable
    k = seed
    while len(variables) < 2 * n:
        k += 1
        kind = rng.choice([x for x, have in (("n", nums), ("a", arrays), ("b", bools)) if have])
        name = f"v{len(variables)}"
        cond = name
        if kind == "n":
            path, topic, lo, hi = rng.choice(nums)
            form = NUMBER_FORMS[k % len(NUMBER_FORMS)].format(p=path, t=topic)
            cmp = f"{rng.choice(['<', '<=', '>', '>='])} {_threshold(rng, lo, hi)}"
            expr, cond = ((form, f"{name} {cmp}") if form.startswith(WHOLE)
                          else (f"{form} {cmp}", name))
        elif kind == "a":
            path, topic, lo, hi = rng.choice(arrays)
            form = ARRAY_FORMS[k % len(ARRAY_FORMS)].format(p=path, c=_threshold(rng, lo, hi))
            expr = f"{form} > {_threshold(rng, lo, hi)}"
        else:
            path, topic = rng.choice(bools)
            expr = BOOL_FORMS[k % len(BOOL_FORMS)].format(p=path)
            if expr.startswith("count_of_messages("):
                expr, cond = expr[:expr.index(" >")], f"{name} > 0"
        variables[name] = expr
        conditions.append(cond)
    names = conditions
    rows = []
    for i in range(n):
        a, b = names[2 * i], names[2 * i + 1]
        template = TEMPLATES[(seed + i) % len(TEMPLATES)]
        if " mode " in template and " " in a:  # a mode is a name
            template = TEMPLATES[0]
        rows.append(f"G{i}: " + template.format(a=a, b=b) + "\n")
    fret = "".join(rows)
    span = doc["duration_s"] or 0.0
    period = max(0.001, min(1.0, span / 300)) if span else 0.1
    busiest = max(doc["topics"], key=lambda t: t["messages"])["topic"]
    tick = (f'period = "{period * 1000:.0f} ms"' if seed % 3 else
            f"topic = {json.dumps(busiest)}")
    binds = "".join(f"{k} = {json.dumps(v)}\n" for k, v in variables.items())
    return fret, f"[tick]\n{tick}\n[variables]\n{binds}"


def generated_case(log: Path, seed: int) -> Case | None:
    """A :class:`Case` of ``log`` with the set :func:`generated_set` draws for it."""
    got = generated_set(inspect_log(str(log)), seed)
    if got is None:
        return None
    name = str(log.relative_to(DATA)) if PRESENT and DATA in log.parents else log.name
    return Case(f"{name}#{seed}", log, *got)


# --------------------------------------------------------------------------- audits
def write(folder: Path, case: Case, fret: str | None = None, bindings: str | None = None
          ) -> Path:
    """The case's requirement file and bindings in ``folder``; the .fret file's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "r.fret").write_text(case.fret if fret is None else fret)
    (folder / "r.bindings.toml").write_text(case.bindings if bindings is None else bindings)
    return folder / "r.fret"


def audit(fret: Path, log: Path, **config) -> dict:
    """The audit JSON of ``log`` with the requirements of ``fret`` (bindings beside it)."""
    plan = load_plan(AuditConfig(requirements=(str(fret),), **config))
    return audit_log(plan, str(log)).to_json()


def verdicts(doc: dict) -> dict[str, dict]:
    """Requirement -> its verdict object of the audit JSON of one log, without
    :data:`WHERE`."""
    return {v["requirement"]: {k: x for k, x in v.items() if k not in WHERE}
            for v in doc["verdicts"]}


def lines(fret: str) -> list[str]:
    """The requirements of a .fret text, each with its indented lines (rationale ...):
    blocks that start with ``ID:`` at column 1 (declarations and comments kept apart)."""
    out: list[str] = []
    for x in fret.splitlines():
        if not x.strip() or x.lstrip().startswith(("#", "@")):
            continue
        if x[0].isspace() and out:
            out[-1] += "\n" + x
        elif not x[0].isspace():
            out.append(x)
    return out


def alone_files(fret: str) -> list[tuple[str, str]]:
    """(id, text) per requirement of a .fret text: the text with every other requirement's
    lines blank, so the requirement keeps its line (its ``source`` and the file:line of its
    diagnostics)."""
    rows = fret.splitlines()
    starts = [i for i, x in enumerate(rows) if x.strip() and not x[0].isspace()
              and not x.lstrip().startswith(("#", "@"))]
    out = []
    for _k, i in enumerate(starts):
        end = next((j for j in range(i + 1, len(rows)) if rows[j].strip() and
                    not rows[j][0].isspace()), len(rows))
        keep = set(range(i, end)) | {j for j, x in enumerate(rows) if x.lstrip().startswith("@")}
        out.append((rows[i].split(":", 1)[0].strip(),
                    "".join((x if j in keep else "") + "\n" for j, x in enumerate(rows))))
    return out


def header(fret: str) -> str:
    """The declaration lines of a .fret text (``@tick_period`` ...)."""
    return "".join(x + "\n" for x in fret.splitlines() if x.lstrip().startswith("@"))


def reversed_bindings(bindings: str) -> str:
    """The binding file with the entries of its ``[variables]`` table in reverse order."""
    head, sep, body = bindings.partition("[variables]\n")
    rows = body.splitlines()
    end = next((i for i, r in enumerate(rows) if r.startswith("[")), len(rows))
    return head + sep + "\n".join(list(reversed(rows[:end])) + rows[end:]) + "\n"


def corrupt_chunk(log: Path, out: Path, which: float) -> tuple[int, int, frozenset] | None:
    """``log`` (an indexed MCAP) with one byte flipped in the chunk at fraction ``which`` of
    its chunks (the middle one for 0.5): (its message start and end time, its channels'
    topics), or None when the log has fewer than 3 chunks."""
    from mcap.reader import make_reader

    with open(log, "rb") as f:
        summary = make_reader(f).get_summary()
    if summary is None or len(summary.chunk_indexes) < 3:
        return None
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.message_start_time)
    ci = chunks[min(len(chunks) - 2, max(1, int(len(chunks) * which)))]
    data = bytearray(log.read_bytes())
    data[ci.chunk_start_offset + ci.chunk_length // 2] ^= 0x40
    out.write_bytes(bytes(data))
    topics = frozenset(summary.channels[c].topic for c in ci.message_index_offsets)
    return ci.message_start_time, ci.message_end_time, topics


def rechunked(log: Path, out: Path, chunks: int = 10) -> Path:
    """``log`` (MCAP) rewritten with the same channels and messages in about ``chunks``
    chunks (uncompressed), so that corrupting one leaves a gap between two halves."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    size = max(1024, log.stat().st_size // chunks)
    with open(log, "rb") as f, open(out, "wb") as o:
        r = make_reader(f)
        w = Writer(o, compression=CompressionType.NONE, chunk_size=size)
        w.start(profile="", library="fretc tests")
        ids = {}
        for sc, ch, m in r.iter_messages(log_time_order=True):
            if ch.id not in ids:
                sid = w.register_schema(sc.name, sc.encoding, sc.data) if sc else 0
                ids[ch.id] = w.register_channel(ch.topic, ch.message_encoding, sid)
            w.add_message(ids[ch.id], m.log_time, m.data, m.publish_time, m.sequence)
        w.finish()
    return out


def flip(data: bytes, seed: str) -> bytes:
    """``data`` with one random bit flipped (seeded)."""
    rng = random.Random(zlib.crc32(seed.encode()))
    b = bytearray(data)
    i = rng.randrange(len(b))
    b[i] ^= 1 << rng.randrange(8)
    return bytes(b)


__all__ = ["Case", "shipped_cases", "real_cases", "foreign_logs", "conformance_logs",
           "generated_set", "generated_case", "write", "audit", "verdicts", "lines",
           "alone_files",
           "header", "reversed_bindings", "corrupt_chunk", "rechunked", "flip"]


# --------------------------------------------------------------------------- the watch's clock
def tick_by_tick(source, bindings, groups):
    """:func:`fretc.signals.sample_blocks`'s result computed by the tick-by-tick clock of
    ``fretc watch`` (:func:`fretc.signals.sample_groups`), one tick a block: patched into
    the audit's passes, it audits a log on the watch's sampling."""
    import numpy as np

    from fretc.signals import sample_groups
    from fretc.signals.blocks import TickBlock

    g = sample_groups(source, bindings, groups)
    g.per_tick = {key: set() for key in groups}
    ticks, count = g._iter, {}

    def blocks():
        for key, tick in ticks:
            i = count[key] = count.get(key, -1) + 1
            values = {n: np.array([v], dtype=np.bool_ if type(v) is bool else np.float64)
                      for n, v in tick.values.items()}
            log_times = {t: np.array([lt], dtype=np.int64) for t, lt in tick.log_times.items()}
            yield key, TickBlock(i, np.array([tick.time], dtype=np.int64), values, log_times)

    g._iter = blocks()
    return g
