"""Python's full garbage collections made rarer while one log is audited (and, in
``fretc audit``, while its verdicts are printed and written).

An audit keeps what it has read until it judges it (ticks, held messages, the rows of
entities, the verdicts of every entity): on a log of messages carrying arrays of structures
(obstacle tracks, joint states, diagnostics) that is millions of objects, and CPython runs a
full (generation 2) collection, which walks every one of them, each time the objects that
survived the young generations grow by a quarter (CPython's ``gc`` module, "threshold2";
the young generations are untouched). On ``bench/bench_audit.py``'s 100,000-obstacle log the
full collections were a fifth of the command's CPU without entities and a third with them;
after the audit, printing the 1,001 violations among its 100,001 verdicts ran one more, a
third of a second.
"""

from __future__ import annotations

import functools
import gc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar, cast

__all__ = ["FULL_EVERY", "fewer_full_collections", "with_fewer_full_collections"]

F = TypeVar("F", bound=Callable[..., Any])

#: Collections of the middle generation between two full collections while a log is audited
#: (Python's default is 10)
FULL_EVERY = 1000


@contextmanager
def fewer_full_collections() -> Iterator[None]:
    """Within the block, a full collection after :data:`FULL_EVERY` collections of the
    middle generation instead of Python's threshold (cycles among new objects are still
    freed by the young collections). The thresholds are restored after, unless changed
    meanwhile; nested blocks, or a threshold already as high, change nothing."""
    t0, t1, t2 = gc.get_threshold()
    if t2 >= FULL_EVERY:
        yield
        return
    gc.set_threshold(t0, t1, FULL_EVERY)
    try:
        yield
    finally:
        if gc.get_threshold() == (t0, t1, FULL_EVERY):
            gc.set_threshold(t0, t1, t2)


def with_fewer_full_collections(func: F) -> F:
    """``func`` run within :func:`fewer_full_collections` (a command that audits logs and
    then prints and writes their verdicts: a full collection would walk every verdict).
    Returns what ``func`` returns and raises what it raises; Python's thresholds
    (``gc.set_threshold``) are given back either way."""
    @functools.wraps(func)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        with fewer_full_collections():
            return func(*args, **kwargs)

    return cast(F, wrapped)
