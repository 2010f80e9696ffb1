"""The rendered text of a monitor module kept on disk between runs, as
:mod:`fretc.compiler.code_cache` keeps its bytecode.

Every ``fretc audit`` renders its requirements' monitor module with Jinja before it checks and
loads it; loading Jinja and rendering cost about 40 ms of CPU at each start, the same work
each time for unchanged requirements. The text is a function of what the templates are fed
and of the code that feeds and renders them, so :func:`rendered` keys an entry by all of it:

Design notes: ARCHITECTURE.md, `compiler/text_cache.py`."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

from fretc.common import cache
from fretc.common.libraries import package_init

__all__ = ["rendered"]

KIND = "monitor-text"
_MAGIC = b"fretc monitor-text 1\n"
_HERE = os.path.dirname(os.path.abspath(__file__))
_TEMPLATES = os.path.join(os.path.dirname(_HERE), "templates")
_CODE_KEY: str | None = None


def _code_key() -> str:
    """A key of the code that renders a module (computed once a process): the templates,
    the modules of :mod:`fretc.compiler`, Jinja's ``__init__.py`` and Python's version."""
    global _CODE_KEY
    if _CODE_KEY is None:
        paths = [os.path.join(_TEMPLATES, n) for n in sorted(os.listdir(_TEMPLATES))
                 if n.endswith(".j2")]
        paths += [os.path.join(_HERE, n) for n in sorted(os.listdir(_HERE)) if n.endswith(".py")]
        _CODE_KEY = cache.files_key(KIND, paths + [package_init("jinja2")], sys.version)
    return _CODE_KEY


def rendered(module_name: str, inputs: str, monitors: Sequence[Any],
             render: Callable[[], str]) -> str:
    """The module text ``render()`` gives for ``inputs`` (the ``repr`` of all the template's
    input), from the cache when a previous render of ``module_name`` had the same inputs and
    code; each monitor's ``shape`` (its index in the module's ``_SHAPES``) is set as
    ``render`` sets it. Otherwise ``render()`` is called and its text kept. Raises what
    ``render`` raises."""
    name = cache.key_of(KIND, module_name)
    made_from = cache.digest("\x00".join((_code_key(), module_name, inputs)).encode(
        "utf-8", "surrogatepass"))
    payload = cache.read_sealed(KIND, name, _MAGIC, made_from)
    if payload is not None:
        try:
            got = json.loads(payload)
            text, shapes = got["text"], got["shapes"]
        except (ValueError, KeyError, TypeError):
            got = None
        if (got is not None and isinstance(text, str) and isinstance(shapes, list)
                and len(shapes) == len(monitors)):
            for m, shape in zip(monitors, shapes):
                m.shape = shape
            return text
    text = render()
    cache.write_sealed(KIND, name, _MAGIC, made_from, json.dumps(
        {"text": text, "shapes": [m.shape for m in monitors]}).encode("utf-8", "surrogatepass"))
    return text
