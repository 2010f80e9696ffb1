"""Twists: outputs the shield scales together, so that a corrected robot keeps its path.

Design notes: ARCHITECTURE.md, `shield/twists.py`."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Collection, Sequence
from pathlib import Path

from fretc.shield.plan import ShieldError

__all__ = ["twists_of", "twists_where", "check_twists"]


def _where(text: str, source: str) -> str:
    """``source:line:col`` of the ``twists`` key in the binding file's ``text`` (the
    file's name alone when it is not found)."""
    for i, line in enumerate(text.splitlines(), start=1):
        m = re.match(r"\s*(twists)\s*=", line)
        if m:
            return f"{source}:{i}:{m.start(1) + 1}"
    return source


def twists_where(bindings_file: str | Path | None) -> str:
    """``file:line:col: [shield] twists`` of a binding file's key (what a refusal of a twist
    names), ``[shield] twists`` without a file."""
    if bindings_file is None:
        return "[shield] twists"
    text = Path(bindings_file).read_text(encoding="utf-8")
    return f"{_where(text, str(bindings_file))}: [shield] twists"


def twists_of(bindings_file: str | Path | None) -> list[list[str]]:
    """The ``[shield] twists`` list of a binding file: each twist the output variables
    scaled together (empty when the file or the key is absent).

    Raises:
        ShieldError: not a list of lists of at least two variable names (``file:line:col``
            of the key)."""
    if bindings_file is None:
        return []
    text = Path(bindings_file).read_text(encoding="utf-8")
    table = tomllib.loads(text).get("shield", {})
    listed = table.get("twists", []) if isinstance(table, dict) else []
    if not isinstance(listed, list) or not all(
            isinstance(t, list) and len(t) >= 2 and all(isinstance(v, str) and v for v in t)
            for t in listed):
        raise ShieldError(f"{_where(text, str(bindings_file))}: [shield] twists must list "
                          "the outputs of each twist, at least two names each, e.g. "
                          "[[\"linear_velocity\", \"angular_velocity\"]]")
    return [list(t) for t in listed]


def check_twists(twists: Sequence[Sequence[str]], outputs: Sequence[str],
                 numbers: Collection[str], integers: Collection[str],
                 booleans: Collection[str], where: str = "[shield] twists"
                 ) -> list[list[str]]:
    """``twists`` checked against the shield's ``outputs``: each names declared outputs, at
    least two, none twice nor in two twists; none a boolean (``booleans``: read as one by a
    requirement) or a whole number (``integers``); ``numbers`` (the variables requirements
    read as numbers) are numbers, an output no requirement reads is taken for one. ``where``
    begins a refusal (:func:`twists_where`).

    Raises:
        ShieldError: naming the twist, the variable and why."""
    seen: dict[str, int] = {}
    out: list[list[str]] = []
    for k, t in enumerate(twists):
        names = list(t)
        shown = "[" + ", ".join(names) + "]"
        if len(names) < 2:
            raise ShieldError(f"{where}: {shown} names fewer than two outputs")
        for v in names:
            if v not in outputs:
                raise ShieldError(f"{where}: {shown} names {v}, not an output ("
                                  + ", ".join(outputs) + ")")
            if v in seen:
                raise ShieldError(f"{where}: {v} is named twice"
                                  + ("" if seen[v] == k else " (in two twists: a speed "
                                     "has one path)"))
            seen[v] = k
            if v in booleans and v not in numbers:
                raise ShieldError(f"{where}: {shown}: {v} is a boolean (a twist "
                                  "scales speeds)")
            if v in integers:
                raise ShieldError(f"{where}: {shown}: {v} takes whole numbers, "
                                  "which scaling does not keep")
        out.append(names)
    return out
