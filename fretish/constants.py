"""Named durations: ``upon too_close the robot shall within T_stop satisfy stopped``, the
value declared once as a constant, in the ``.fret`` file (``@constant T_stop 1.5 s``) or in
the bindings file (``[constants] T_stop = "1.5 s"``). FRET's users asked for it (FRET issue
30: a variable that represents a time constant); FRET itself takes only numbers.

A constant's value is a duration as FRETish writes one (``1.5 s``, ``500 milliseconds``,
``15 ticks``); it is converted to ticks as the same number written in the sentence would be
(:func:`fretc.compiler.semantics.duration_ticks`), so ``within T_stop`` with ``T_stop = 1 s``
means exactly ``within 1 second``.
"""

from __future__ import annotations

import dataclasses
import re

from fretc.fretish import ast as A

__all__ = ["CONSTANT_NAME", "parse_constant", "resolve", "unresolved", "constant_notes"]

#: A constant's name: an identifier (as a FRETish variable).
CONSTANT_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def parse_constant(text: str) -> tuple[str, str]:
    """``"1.5 s"`` -> ``("1.5", "seconds")``: the amount as written and the canonical unit,
    read by FRETish's own duration grammar.

    Raises:
        ValueError: not a number and a unit FRETish knows (the message says what is).
    """
    from fretc.common.errors import FretishError

    from fretc.fretish.parser import parse

    try:
        d = parse(f"the c shall within {text.strip()} satisfy p").timing.duration
    except FretishError:
        d = None
    if d is not None and d.resolved:
        return d.amount, d.unit
    from fretc.common.units import parse_seconds  # the bindings' spelling: "1.5 s", "100 ms"

    try:
        seconds = parse_seconds(text)
    except ValueError:
        raise ValueError(f"{text.strip()!r} is not a duration (write e.g. \"1.5 s\", "
                         "\"500 milliseconds\" or \"15 ticks\")") from None
    den = seconds.denominator
    while den % 2 == 0:
        den //= 2
    while den % 5 == 0:
        den //= 5
    if den != 1:
        raise ValueError(f"{text.strip()!r} is {seconds} s, not a decimal number of seconds")
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 60
        amount = format(Decimal(seconds.numerator) / Decimal(seconds.denominator), "f")
    return amount, "seconds"


def unresolved(req: A.Requirement | None) -> str | None:
    """The name of ``req``'s duration when it is a constant not yet resolved, else None."""
    d = req.timing.duration if req is not None and not req.freeform else None
    return d.name if d is not None and not d.resolved else None


def resolve(req: A.Requirement, constants: dict[str, tuple[str, str]]) -> A.Requirement:
    """``req`` with its named duration given the value of ``constants[name]`` (name ->
    (amount, unit)); ``req`` itself when it has none or the name is not there."""
    name = unresolved(req)
    if name is None or name not in constants:
        return req
    amount, unit = constants[name]
    duration = req.timing.duration
    assert duration is not None  # unresolved() named it
    d = dataclasses.replace(duration, amount=amount, unit=unit)
    return dataclasses.replace(req, timing=dataclasses.replace(req.timing, duration=d))


def constant_notes(req: A.Requirement | None) -> list[str]:
    """``["T_stop = 1.5 seconds"]`` for a requirement whose duration is a resolved constant
    (every output shows the value used), else ``[]``."""
    d = req.timing.duration if req is not None and not req.freeform else None
    if d is None or d.name is None or not d.resolved:
        return []
    return [f"{d.name} = {d.amount} {d.unit}"]
