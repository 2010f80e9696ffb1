"""Faults seeded into fretc in this process, for the validation suite's mutation run: each
is a context manager that replaces one piece of fretc (an attribute of one of its modules)
by a broken one and puts the original back on exit, whatever happens inside.

The faults stand for the defects a qualification must show the suite would notice (IEC
61508-3 7.4.4.5 asks how a tool can fail; a suite that no fault makes fail shows nothing):
in the grammar, FRET's semantics as the judge applies it, the formulas and their printer,
durations, the tick rules, windows and folds of the signals, entity keys, the CSV and MCAP
readers, the audit's verdict words and statistics, the Python, C and AJPF generators, the
shield's Python form, the output files and the gaps of ``fretc watch`` (the failure
analysis, docs/qualification/, maps each to the failure it stands for).
``FRETC_QUALIFY_SEED_FAULT=NAME`` seeds one of them for a whole run of ``fretc qualify``
(:func:`fretc.qualification.suite.qualify`): the test that the suite fails then, naming the
requirement, stands for an installation with that defect.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Fault:
    """A seeded fault: ``name`` (the word ``FRETC_QUALIFY_SEED_FAULT`` takes), ``where``
    (the part of fretc broken), ``what`` (the defect, one sentence) and ``seed()``, a
    context manager that holds the fault while it is entered; ``first`` the checks to try
    first."""

    name: str
    where: str
    what: str
    seed: Callable[[], contextlib.AbstractContextManager[None]]
    #: the checks the mutation run tries first (the one meant to detect it); the others run
    #: after them while none has failed, so the order changes the time, never the answer
    first: tuple[str, ...] = ()


@contextlib.contextmanager
def _replaced(module: Any, attr: str, value: Any) -> Iterator[None]:
    """``module.attr`` is ``value`` inside the block, its own value again after it."""
    old = getattr(module, attr)
    setattr(module, attr, value)
    try:
        yield
    finally:
        setattr(module, attr, old)


@contextlib.contextmanager
def _trigger_fault() -> Iterator[None]:
    """The judge's regular conditions trigger at every tick where they hold (as
    ``whenever``), not only where they become true."""
    from fretc.monitors import interval

    original = interval.trigger_ticks

    def broken(cond: str, C: Any, I: Any, starts: Any, last_ci: bool) -> Any:
        return original("holding" if cond == "regular" else cond, C, I, starts, last_ci)

    with _replaced(interval, "trigger_ticks", broken):
        yield


@contextlib.contextmanager
def _next_fault() -> Iterator[None]:
    """The formulas of ``at the next timepoint`` are built as those of ``immediately``
    (the template's timing mistaken)."""
    from fretc.compiler import instantiate, semantics

    original = semantics.template_parts

    def broken(req: Any, tick_period: Any) -> tuple[str, str, str, int | None, list[str]]:
        scope, cond, timing, n, warnings = original(req, tick_period)
        return scope, cond, "immediately" if timing == "next" else timing, n, warnings

    with _replaced(semantics, "template_parts", broken), \
            _replaced(instantiate, "template_parts", broken):
        yield


class _LeftHold:
    """numpy as :mod:`fretc.signals.blocks` sees it, but ``searchsorted`` always searching
    from the left: a message exactly at a tick is no longer held by that tick."""

    def __init__(self, np: Any):
        self._np = np

    def __getattr__(self, name: str) -> Any:
        return getattr(self._np, name)

    def searchsorted(self, a: Any, v: Any, side: str = "left", sorter: Any = None) -> Any:
        """numpy's ``searchsorted`` with ``side`` forced to ``"left"``."""
        return self._np.searchsorted(a, v, side="left", sorter=sorter)


@contextlib.contextmanager
def _hold_fault() -> Iterator[None]:
    """Sample and hold: a tick holds the newest message strictly before it."""
    from fretc.signals import blocks

    with _replaced(blocks, "np", _LeftHold(blocks.np)):
        yield


@contextlib.contextmanager
def _csv_fault() -> Iterator[None]:
    """The CSV reader reads the cells ``true`` as false and ``false`` as true."""
    from fretc.logs.csv import read

    words = dict(read._BOOL_WORDS)
    words["true"], words["false"] = words["false"], words["true"]
    with _replaced(read, "_BOOL_WORDS", words):
        yield


@contextlib.contextmanager
def _wrapped(module: Any, attr: str, wrap: Callable[[Any], Any]) -> Iterator[None]:
    """``module.attr`` is ``wrap(original)`` inside the block, its own value after it."""
    with _replaced(module, attr, wrap(getattr(module, attr))):
        yield


@contextlib.contextmanager
def _precedence_fault() -> Iterator[None]:
    """The parser builds ``&`` as ``|`` and ``|`` as ``&``."""
    from fretc.fretish import parser

    ops = dict(parser._BINOPS)
    ops["AMP"], ops["BAR"] = ops["BAR"], ops["AMP"]
    with _replaced(parser, "_BINOPS", ops):
        yield


@contextlib.contextmanager
def _duration_fault() -> Iterator[None]:
    """A duration in time units converts to one tick more than it is long."""
    from fretc.compiler import semantics

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> Any:
            n = original(*args, **kwargs)
            return n + 1 if isinstance(n, int) and n > 1 else n
        return broken

    with _wrapped(semantics, "duration_ticks", wrap):
        yield


@contextlib.contextmanager
def _spot_printer_fault() -> Iterator[None]:
    """The LTL printer writes ``until`` as the weak until (``U`` as ``W``): ft_inf accepts
    runs whose obligation never ends."""
    from fretc.compiler import printers

    with _wrapped(printers, "to_spot",
                  lambda original: lambda node: original(node).replace(" U ", " W ")):
        yield


@contextlib.contextmanager
def _status_fault() -> Iterator[None]:
    """The generated Python monitors never report a definite violation (their status word
    ``violated`` printed as ``unknown``)."""
    from fretc.compiler import codegen

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> str:
            text: str = original(*args, **kwargs)
            return text.replace("'violated'", "'unknown'").replace('"violated"', '"unknown"')
        return broken

    with _wrapped(codegen, "render_module", wrap):
        yield


@contextlib.contextmanager
def _c_string_fault() -> Iterator[None]:
    """The C generator writes ids and texts into string literals unescaped."""
    from fretc.compiler import c_codegen

    with _replaced(c_codegen, "c_string", lambda text: '"' + text + '"'):
        yield


@contextlib.contextmanager
def _psl_fault() -> Iterator[None]:
    """AJPF's properties lose the parentheses of their binary sub-formulas."""
    from fretc.compiler import ajpf

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> str:
            text: str = original(*args, **kwargs)
            return text.replace("(", "").replace(")", "") if "[]" in text else text
        return broken

    with _wrapped(ajpf, "to_ajpf", wrap):
        yield


def _words(change: dict[str, str]) -> Callable[[], contextlib.AbstractContextManager[None]]:
    """A fault: the audit's JSON reports the verdict words of ``change`` as others."""
    @contextlib.contextmanager
    def fault() -> Iterator[None]:
        from fretc.audit import verdict

        def wrap(original: Any) -> Any:
            def broken(self: Any, *args: Any, **kwargs: Any) -> dict:
                doc: dict = original(self, *args, **kwargs)
                if doc.get("verdict") in change:
                    doc["verdict"] = change[doc["verdict"]]
                return doc
            return broken

        with _wrapped(verdict.Verdict, "to_json", wrap):
            yield
    return fault


@contextlib.contextmanager
def _window_fault() -> Iterator[None]:
    """A window over time keeps a message exactly its span old (closed on the left)."""
    from fretc.signals import windows

    with _wrapped(windows.SlidingWindow, "_evict",
                  lambda original: lambda self, t: original(self, t - 1)):
        yield


@contextlib.contextmanager
def _fold_fault() -> Iterator[None]:
    """The aggregations over the messages between ticks fold the last message only."""
    from fretc.signals import between_ticks
    from fretc.signals.bindings import binding

    def wrap(original: Any) -> Any:
        return lambda aggregate, values: original(aggregate, list(values)[-1:])

    with _wrapped(binding, "fold", wrap), _wrapped(between_ticks, "fold", wrap):
        yield


@contextlib.contextmanager
def _chunk_cap_fault() -> Iterator[None]:
    """The cap on a chunk's uncompressed size is not applied (any size is decompressed)."""
    from fretc.logs.mcap import records

    with _replaced(records, "max_chunk_bytes", lambda: 1 << 62):
        yield


@contextlib.contextmanager
def _mcap_chunk_fault() -> Iterator[None]:
    """The MCAP reader drops the last message of every chunk it reads through the index
    (message by message and in columns)."""
    from fretc.logs.mcap import columns, source

    def messages(original: Any) -> Any:
        return lambda self, *args, **kwargs: original(self, *args, **kwargs)[:-1]

    def table(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> Any:
            data, heads, lengths = original(*args, **kwargs)
            return data, heads[:-1], lengths[:-1]
        return broken

    with _wrapped(source.McapSource, "_read_chunk", messages), \
            _wrapped(columns, "chunk_message_table", table):
        yield


@contextlib.contextmanager
def _interval_fault() -> Iterator[None]:
    """Statistical verdicts take the normal approximation (Wald) for Clopper-Pearson's
    exact interval."""
    import math

    from fretc.audit.fleet import intervals

    def wald(k: float, n: float, confidence: float) -> tuple[float, float]:
        p = k / n
        half = 1.959963984540054 * math.sqrt(p * (1 - p) / n)
        return max(0.0, p - half), min(1.0, p + half)

    with _replaced(intervals, "_beta_interval", wald):
        yield


@contextlib.contextmanager
def _link_fault() -> Iterator[None]:
    """Output files are written through a link planted at their name (to its target)."""
    import os

    from fretc.common import outputs

    def wrap(original: Any) -> Any:
        return lambda path, *args, **kwargs: original(os.path.realpath(path), *args, **kwargs)

    with _wrapped(outputs, "open_output", wrap):
        yield


@contextlib.contextmanager
def _witness_fault() -> Iterator[None]:
    """``fretc check`` writes its witnesses' boolean cells negated."""
    from fretc.check import witness

    def wrap(original: Any) -> Any:
        return lambda v: original(not v) if isinstance(v, bool) else original(v)

    with _wrapped(witness, "_cell", wrap):
        yield


@contextlib.contextmanager
def _shield_pass_fault() -> Iterator[None]:
    """The shield's Python form passes every proposal on, corrections included (its check
    of a proposal always says safe)."""
    from fretc.shield import emit_python

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> str:
            text: str = original(*args, **kwargs)
            return text.replace("if not unk and safe_in_all(prop):", "if True:")
        return broken

    with _wrapped(emit_python, "_runtime_body", wrap):
        yield


@contextlib.contextmanager
def _ros2_forward_fault() -> Iterator[None]:
    """The shield's ROS 2 node answers a proposal heard between ticks with the proposal
    itself, not the shield's decision (a command no shield vetted on the bus)."""
    from fretc.shield import emit_ros2

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> str:
            text: str = original(*args, **kwargs)
            return text.replace(
                "decision, messages = self.shield.answer(t)",
                "decision, messages = self.shield.answer(t)\n            messages = "
                "[(c, self.shield.proposed.get(c, m)) for c, m in messages]")
        return broken

    with _wrapped(emit_ros2, "node_source", wrap):
        yield


@contextlib.contextmanager
def _gwendolen_latch_fault() -> Iterator[None]:
    """The Gwendolen agent's Java machine latches its first output atom: once decided
    true it stays true (the stop never released)."""
    from fretc.shield import emit_gwendolen

    def latched(java: str) -> str:
        return java.replace(
            "        return new int[][] {out, next, {broken ? 1 : 0}};",
            "        LATCH = LATCH || out[0] == 1;\n        out[0] = LATCH ? 1 : out[0];\n"
            "        return new int[][] {out, next, {broken ? 1 : 0}};").replace(
            "    public static void main(", "    static boolean LATCH = false;\n\n"
            "    public static void main(")

    def wrap(original: Any) -> Any:
        def broken(*args: Any, **kwargs: Any) -> dict[str, str]:
            files: dict[str, str] = original(*args, **kwargs)
            return {name: latched(text) if name.endswith("_shield.java") else text
                    for name, text in files.items()}
        return broken

    with _wrapped(emit_gwendolen, "render_gwendolen", wrap):
        yield


@contextlib.contextmanager
def _entity_key_fault() -> Iterator[None]:
    """An entity's integer key is read through a float64 (two uint64 ids past 2**53 that
    one double holds are one entity), by the key's binding and by the fast key reader."""
    from fretc.audit.entities import rows
    from fretc.signals.bindings import extract

    def double(v: Any) -> Any:
        return float(v) if type(v) is int else v

    def one(original: Any) -> Any:
        return lambda v: double(original(v))

    def call(original: Any) -> Any:
        def broken(self: Any, data: Any) -> Any:
            keys = original(self, data)
            return None if keys is None else [double(v) for v in keys]
        return broken

    def batch(original: Any) -> Any:
        def broken(self: Any, datas: Any) -> Any:
            got = original(self, datas)
            return None if got is None else ([double(v) for v in got[0]], got[1])
        return broken

    with _wrapped(extract, "entity_key", one), _wrapped(rows, "entity_key", one), \
            _wrapped(rows.KeyReader, "__call__", call), _wrapped(rows.KeyReader, "batch", batch):
        yield


@contextlib.contextmanager
def _watch_gap_fault() -> Iterator[None]:
    """The watch forgets the gaps of a lost connection, an overflowing queue and an
    undecodable message when it judges the run and records it: the values read before a
    gap are held over it."""
    from fretc.live import absence, watch

    def wrap(original: Any) -> Any:
        return lambda src: [g for g in original(src) if g.cause != "connection_gap"]

    with _wrapped(absence, "run_gaps", wrap), _wrapped(watch, "run_gaps", wrap):
        yield


@contextlib.contextmanager
def _csv_extent_fault() -> Iterator[None]:
    """Each read of a CSV trace reads the file as it is then (the extent of the audit's
    first read not passed on): a trace still being written is judged over more rows by
    the later reads."""
    from fretc.logs.csv.source import CsvSource

    def wrap(original: Any) -> Any:
        return lambda self, *args, **kwargs: original(self, *args, **{**kwargs, "extent": None})

    with _wrapped(CsvSource, "__init__", wrap):
        yield


#: the faults of the mutation run, by name
FAULTS: dict[str, Fault] = {f.name: f for f in (
    Fault("semantics-trigger", "fretc.monitors.interval (the audit's judge)",
          "a regular condition (upon, when, if) triggers at every tick where it holds",
          _trigger_fault,
          first=("semantics-judge",)),
    Fault("semantics-next", "fretc.compiler.semantics (FRET's templates)",
          "'at the next timepoint' is formalized as 'immediately'", _next_fault,
          first=("semantics-formulas",)),
    Fault("tick-hold", "fretc.signals.blocks (the tick rules' sample and hold)",
          "a message exactly at a tick's time is not held by that tick", _hold_fault,
          first=("mcap-ticks",)),
    Fault("reader-csv", "fretc.logs.csv.read (the CSV reader)",
          "the cells true and false are read the other way round", _csv_fault,
          first=("audit-keys",)),
    Fault("grammar-precedence", "fretc.fretish.parser (the grammar's operators)",
          "'&' is built as '|' and '|' as '&'", _precedence_fault,
          first=("grammar-precedence",)),
    Fault("semantics-duration", "fretc.compiler.semantics (durations)",
          "a duration converts to one tick more than it is long", _duration_fault,
          first=("semantics-formulas",)),
    Fault("formulas-until", "fretc.compiler.printers (the LTL printer)",
          "'U' is printed as the weak until 'W'", _spot_printer_fault,
          first=("semantics-ft-inf",)),
    Fault("monitors-status", "fretc.compiler.codegen (the Python monitors)",
          "the monitors never report a definite violation", _status_fault,
          first=("monitors-ltl3",)),
    Fault("c-strings", "fretc.compiler.c_codegen (the C monitors)",
          "ids and texts are written into C string literals unescaped", _c_string_fault,
          first=("generated-escaping",)),
    Fault("psl-parentheses", "fretc.compiler.ajpf (AJPF's properties)",
          "binary sub-formulas lose their parentheses", _psl_fault,
          first=("ajpf-psl",)),
    Fault("verdict-vacuous", "fretc.audit.verdict (the audit's words)",
          "a vacuous verdict is reported satisfied", _words({"vacuous": "satisfied"}),
          first=("audit-keys",)),
    Fault("verdict-unknown", "fretc.audit.verdict (the audit's words)",
          "an unknown verdict is reported satisfied", _words({"unknown": "satisfied"}),
          first=("audit-unknown",)),
    Fault("signals-window", "fretc.signals.windows (windows over time)",
          "a window keeps a message exactly its span old", _window_fault,
          first=("bindings-windows",)),
    Fault("signals-fold", "fretc.signals.between_ticks (messages between ticks)",
          "an aggregation folds only the last message", _fold_fault,
          first=("signals-between-ticks",)),
    Fault("reader-mcap-chunk", "fretc.logs.mcap.source (the MCAP reader)",
          "the last message of every indexed chunk is dropped", _mcap_chunk_fault,
          first=("mcap-ticks",)),
    Fault("reader-mcap-cap", "fretc.logs.mcap.records (MCAP chunks)",
          "the cap on a chunk's uncompressed size is not applied", _chunk_cap_fault,
          first=("mcap-chunk-cap",)),
    Fault("statistics-interval", "fretc.audit.fleet.statistics (statistical verdicts)",
          "Wald's approximation replaces the exact Clopper-Pearson interval", _interval_fault,
          first=("audit-statistics",)),
    Fault("outputs-link", "fretc.common.outputs (output files)",
          "an output is written through a link planted at its name", _link_fault,
          first=("outputs-same-bytes",)),
    Fault("check-witness", "fretc.check.witness (fretc check's witnesses)",
          "a witness's boolean cells are written negated", _witness_fault,
          first=("check-witnesses",)),
    Fault("shield-passes", "fretc.shield.emit_python (the shield's Python form)",
          "every proposal is passed on, corrections included", _shield_pass_fault,
          first=("shield-python",)),
    Fault("ros2-proposal-forwarded", "fretc.shield.emit_ros2 (the shield's ROS 2 node)",
          "a proposal heard between ticks is published as proposed, not as decided",
          _ros2_forward_fault, first=("shield-ros2",)),
    Fault("gwendolen-latch", "fretc.shield.emit_gwendolen (the Gwendolen agent's machine)",
          "the agent's machine holds its first output true once it was decided true",
          _gwendolen_latch_fault, first=("shield-gwendolen",)),
    Fault("entity-keys-double", "fretc.signals.bindings.extract (entity keys)",
          "an integer entity key is read through a float64", _entity_key_fault,
          first=("bindings-entity-keys",)),
    Fault("watch-gap-held", "fretc.live.absence (the watched run's gaps)",
          "the values read before a watch's lost messages are held over them", _watch_gap_fault,
          first=("watch-gaps",)),
    Fault("reader-csv-extent", "fretc.logs.csv.source (the CSV reader)",
          "each read of a CSV trace still being written reads its size then",
          _csv_extent_fault, first=("csv-extent",)),
)}
