"""The requirement entries of a ``.fret`` file kept on disk between runs, as Python keeps a
module's bytecode in ``__pycache__``.

Design notes: ARCHITECTURE.md, `fretish/entry_cache.py`."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

from fretc.common import cache, cache_json
from fretc.common.libraries import package_init
from fretc.fretish import ast, entry
from fretc.fretish.entry import RequirementEntry

__all__ = ["cached_entries", "code_key"]

KIND = "fret-entries"
_MAGIC = b"fretc fret-entries 2 json\n"
#: the classes an entry may hold
_CLASSES = cache_json.classes_of(ast, entry)
_HERE = os.path.dirname(os.path.abspath(__file__))
_COMMON = os.path.join(os.path.dirname(_HERE), "common")
#: what else a .fret file's entries depend on (units of durations, the error classes)
_OTHER = ("units.py", "errors.py")
_CODE_KEY: str | None = None


def code_key() -> str:
    """A key of the code that makes a ``.fret`` file's entries: the text of every module of
    :mod:`fretc.fretish` and its grammar, of :mod:`fretc.common.units` and
    :mod:`fretc.common.errors`, and Lark's (its ``__init__.py``,
    :func:`fretc.common.libraries.package_init`) and Python's versions (computed once a
    process)."""
    global _CODE_KEY
    if _CODE_KEY is None:
        names = sorted(n for n in os.listdir(_HERE) if n.endswith((".py", ".lark")))
        paths = ([os.path.join(_HERE, n) for n in names]
                 + [os.path.join(_COMMON, n) for n in _OTHER] + [package_init("lark")])
        _CODE_KEY = cache.files_key(KIND, paths, sys.version)
    return _CODE_KEY


def _name(source: str) -> str:
    return cache.key_of(KIND, source)


def _made_from(source: str, text: str) -> bytes:
    return cache.digest("\x00".join((code_key(), source, text)).encode(
        "utf-8", "surrogatepass"))


def _load(source: str, text: str) -> list[RequirementEntry] | None:
    payload = cache.read_sealed(KIND, _name(source), _MAGIC, _made_from(source, text))
    if payload is None:
        return None
    try:
        got = cache_json.loads(payload, _CLASSES)
    except ValueError:  # not this layout: a miss (the seal makes it unlikely)
        return None
    if not (isinstance(got, list) and all(isinstance(e, RequirementEntry) for e in got)):
        return None
    return got


def _store(source: str, text: str, entries: list[RequirementEntry]) -> bool:
    try:
        payload = cache_json.dumps(entries, _CLASSES)
    except (TypeError, ValueError, RecursionError):  # no JSON form (an error, a class not
        return False                                 # listed, too deep): not kept
    return cache.write_sealed(KIND, _name(source), _MAGIC, _made_from(source, text), payload)


def cached_entries(source: str, text: str, read: Callable[[], list[RequirementEntry]]
                   ) -> list[RequirementEntry]:
    """The entries of the ``.fret`` file named ``source`` whose text is ``text``: those kept
    from an earlier ``read()`` of the same name, text and code, else ``read()``'s (kept when
    every sentence parsed). Raises what ``read`` raises."""
    got = _load(source, text)
    if got is not None:
        return got
    entries = read()
    if all(e.error is None for e in entries):
        _store(source, text, entries)
    return entries
