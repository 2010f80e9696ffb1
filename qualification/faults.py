"""Faults seeded into fretc in this process, for the validation suite's mutation run: each
is a context manager that replaces one piece of fretc (an attribute of one of its modules)
by a broken one and puts the original back on exit, whatever happens inside.

The faults stand for the defects a qualification must show the suite would notice (IEC
61508-3 7.4.4.5 asks how a tool can fail; a suite that no fault makes fail shows nothing):
one in FRET's semantics as the audit's judge applies it, one in the formulas fretc builds,
one in the tick rules (sample and hold) and one in a log reader (the CSV reader's cells).
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
    context manager that holds the fault while it is entered."""

    name: str
    where: str
    what: str
    seed: Callable[[], contextlib.AbstractContextManager[None]]


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


#: the faults of the mutation run, by name
FAULTS: dict[str, Fault] = {f.name: f for f in (
    Fault("semantics-trigger", "fretc.monitors.interval (the audit's judge)",
          "a regular condition (upon, when, if) triggers at every tick where it holds",
          _trigger_fault),
    Fault("semantics-next", "fretc.compiler.semantics (FRET's templates)",
          "'at the next timepoint' is formalized as 'immediately'", _next_fault),
    Fault("tick-hold", "fretc.signals.blocks (the tick rules' sample and hold)",
          "a message exactly at a tick's time is not held by that tick", _hold_fault),
    Fault("reader-csv", "fretc.logs.csv.read (the CSV reader)",
          "the cells true and false are read the other way round", _csv_fault),
)}
