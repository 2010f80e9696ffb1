"""The values of a ``.fret`` file's directives and of their command-line counterparts: a
tick period (``@tick_period``, ``--tick-period``) and lists of FRET variables (``@inputs`` /
``@outputs``, ``--inputs`` / ``--outputs``), whose names that are no identifiers go in double
quotes as FRETish writes them (``"wheel speed"``; FRET's quoted names)."""

from __future__ import annotations

import re
from fractions import Fraction

from fretc.common.units import parse_seconds

__all__ = ["parse_tick_period", "name_tokens", "split_names"]

#: one name of a list: a double-quoted name (any text but a quote) or a bare one (a lone
#: ``"`` starts a bare token of its own, refused), separated by commas or blanks
_NAME_TOKEN = re.compile(r'"([^"]*)"|("?[^\s,"]+|")')
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*")


def parse_tick_period(text: str) -> Fraction:
    """``"<number> <unit>"`` (e.g. ``"100 ms"``, ``"0.05 seconds"``, ``"10 Hz"``) -> seconds,
    exactly: the duration grammar of :mod:`fretc.common.units` (the same as the bindings').

    Raises :class:`ValueError` (with a readable message) for anything else, for ``ticks`` (a
    tick period must be a time) and for a period that is not positive.
    """
    return parse_seconds(text)


def name_tokens(text: str, identifiers: bool = False) -> list[tuple[str, int]]:
    """``(name, offset in text)`` of each name of a list (commas or blanks between names,
    quotes not part of a quoted name); ``identifiers``: a bare name must be a FRETish
    identifier (``@inputs``: ``ROS.ok`` is one, ``load%`` goes in quotes).

    Raises:
        ValueError: ``(why, token, offset)``: a quote not closed, an empty quoted name, a
            bare name that is no identifier (with ``identifiers``)."""
    out = []
    for tok in _NAME_TOKEN.finditer(text):
        bare = tok.group(2)
        if bare is not None and bare.startswith('"') or tok.group(1) == "":
            raise ValueError("its double quote is not closed, or it is empty", tok.group(0),
                             tok.start())
        if identifiers and bare is not None and not _IDENTIFIER.fullmatch(bare):
            raise ValueError("a name that is no identifier goes in double quotes, as the "
                             "requirements write it", bare, tok.start())
        out.append((bare if bare is not None else tok.group(1), tok.start()))
    return out


def split_names(text: str) -> list[str]:
    """The FRET variables of a list (``--inputs A,B``; ``"wheel speed", ok``):
    :func:`name_tokens`' names.

    Raises:
        ValueError: a quote that is not closed, or an empty quoted name (the message names
            the token)."""
    try:
        return [n for n, _at in name_tokens(text)]
    except ValueError as exc:
        why, token, _at = exc.args
        raise ValueError(f"{token!r} in {text!r}: {why}") from None
