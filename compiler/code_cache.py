"""The bytecode of a checked monitor module, kept on disk like Python's ``__pycache__``.

:func:`fretc.compiler.codegen.check_module` compiles a generated module and the step code of each
of its shapes (``_SHAPES``) before it runs them: on the 696 sentences of
``fret_trace_verdicts.jsonl`` that is 0.6 s of CPU, a fifth of a warm ``fretc FILE --emit
monitor``. Regenerating the monitors of an unchanged requirement file gives byte-identical
text, so the check can reuse the code objects of the previous run, as Python reuses a
``.pyc``: only ``compile()`` is memoized; the names check, the load and the two steps of
every monitor still run on every check.

Design notes: ARCHITECTURE.md, `compiler/code_cache.py`."""

from __future__ import annotations

import importlib.util
import marshal
import types

from fretc.common import cache

__all__ = ["load", "store"]

KIND = "monitor-code"
_MAGIC = b"fretc monitor-code 1\n"


def _name(module_name: str) -> str:
    return cache.key_of(KIND, importlib.util.MAGIC_NUMBER.hex(), module_name)


def _text_digest(text: str) -> bytes:
    return cache.digest(text.encode("utf-8", "surrogatepass"))


def load(module_name: str, text: str
         ) -> tuple[types.CodeType, tuple[types.CodeType, ...]] | None:
    """The code objects :func:`store` kept for ``text`` (the module's, then one per shape
    in ``_SHAPES`` order), or None: no entry, an entry for another text, or damaged."""
    payload = cache.read_sealed(KIND, _name(module_name), _MAGIC, _text_digest(text))
    if payload is None:
        return None
    try:
        module_code, shapes = marshal.loads(payload)
    except (ValueError, EOFError, TypeError):
        return None
    if not (isinstance(module_code, types.CodeType) and isinstance(shapes, tuple)
            and all(isinstance(c, types.CodeType) for c in shapes)):
        return None
    return module_code, shapes


def store(module_name: str, text: str, module_code: types.CodeType,
          shapes: list[types.CodeType]) -> bool:
    """Keep the code objects compiled from ``text`` (the module's, then its shapes' in
    ``_SHAPES`` order) for the next :func:`load`; False when the cache is off or not
    writable (never raises for that)."""
    return cache.write_sealed(KIND, _name(module_name), _MAGIC, _text_digest(text),
                              marshal.dumps((module_code, tuple(shapes))))
