"""The checked-in template table: one JSON file per template key under ``compiler/table/``.

FRET ships its formalizations as data (``semantics.json``, generated from its templates);
fretc ships, in the same spirit, the printed formulas of every *template key* (scope,
condition kind, timing, duration class) built with placeholder atoms, as
``compiler/make_table.py`` generates them from :mod:`fretc.compiler.semantics`
(``python -m fretc.compiler.make_table``; ``tests/compiler/test_template_table.py`` fails when
the files are not what that command writes). :mod:`fretc.compiler.instantiate` fills them in.

Design notes: ARCHITECTURE.md, `compiler/template_table.py`."""

from __future__ import annotations

import json
import operator
import os
import re
from collections.abc import Callable, Sequence
from typing import Any

from fretc.fretish import ast as A

__all__ = ["ALL_KEYS", "Template", "file_name", "template", "TABLE_DIR"]

#: format-field numbers: the atoms (mode, condition, stop, response) of ft, of ft_inf and
#: of pt, then the bounds n-2 .. n+3
ATOMS = 4
BOUND0 = 3 * ATOMS  # field of n + MIN_OFFSET
MIN_OFFSET, MAX_OFFSET = -2, 3

TABLE_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "table")

#: every template key: (scope, condition kind, timing, n class: None, 0, 1 or -1 for >= 2)
ALL_KEYS = tuple(
    (scope, cond, timing, n)
    for scope in ("null", "in", "notin", "onlyIn", "after", "before", "onlyAfter",
                  "onlyBefore")
    for cond in ("null", "regular", "holding")
    for timing in ("null", "immediately", "next", "finally", "eventually", "always",
                   "never", "within", "for", "after", "until", "before")
    for n in ((0, 1, -1) if timing in A.DURATION_TIMINGS else (None,)))

FORM_NAMES = ("ft", "ft_inf", "pt", "ft_spot", "ft_inf_spot")


def file_name(key: tuple) -> str:
    """The file of template key ``key`` (as in :data:`ALL_KEYS`) in :data:`TABLE_DIR`,
    e.g. ``in-regular-within-n.json``, ``null-null-always.json``."""
    scope, cond, timing, n = key
    suffix = "" if n is None else "-n" if n == -1 else f"-{n}"
    return f"{scope}-{cond}-{timing}{suffix}.json"


#: a printed form of a template: ``(format, getter)``, ``format % getter(values)`` its text
Form = tuple[str, Callable[[Sequence[Any]], tuple[Any, ...]]]

_FIELD = re.compile(r"\{(\d+)\}")


def compile_text(text: str | None) -> tuple[str, tuple[int, ...]] | None:
    """``(format, order)`` of a template text whose fields are ``{i}``: ``format %
    tuple(values[i] for i in order)`` fills them in (None stays None)."""
    if text is None:
        return None
    order = tuple(int(x) for x in _FIELD.findall(text))
    return _FIELD.sub("%s", text.replace("%", "%%")), order


def _tuples(x):
    """JSON lists back as tuples (the conditions are compared and hashed as tuples)."""
    if type(x) is list:
        return tuple(_tuples(y) for y in x)
    return x


def _picker(order: tuple):
    """``values -> tuple`` of the values at ``order`` (a ``%`` operand)."""
    if not order:
        return lambda values: ()
    if len(order) == 1:
        i = order[0]
        return lambda values: (values[i],)
    return operator.itemgetter(*order)


class Template:
    """The printed forms of one template key with fields for the atoms and bounds: ``ft``,
    ``ft_inf``, ``pt``, ``ft_spot``, ``ft_inf_spot`` are each ``(format, getter)`` (None
    where Spot has no form): ``format % getter(values)`` fills in the twelve atoms' texts
    and the bounds (from field :data:`BOUND0`). ``forms`` holds them as ``(format,
    order)``; ``compared`` is the file's ``fallback`` as tuples. ``json`` and
    ``plain_compared`` are slots for :mod:`fretc.compiler.instantiate` and
    :mod:`fretc.compiler.fallback` to keep what they derive from the template."""

    __slots__ = ("forms", "compared", "json", "plain_compared", "ft", "ft_inf", "pt",
                 "ft_spot", "ft_inf_spot")
    forms: tuple[tuple[str, tuple[int, ...]] | None, ...]
    compared: tuple[Any, ...]
    json: tuple[Any, tuple[str, ...], Any] | None  # (enc, seps, json_format's result)
    plain_compared: tuple[Any, ...] | None
    ft: Form  # the FRET/SMV forms are always there,
    ft_inf: Form
    pt: Form
    ft_spot: Form | None  # a Spot form may not be
    ft_inf_spot: Form | None

    def __init__(self, data: dict):
        self.forms = tuple(compile_text(data[name]) for name in FORM_NAMES)
        self.compared = _tuples(data["fallback"])
        self.json = None
        self.plain_compared = None
        (self.ft, self.ft_inf, self.pt, self.ft_spot, self.ft_inf_spot) = (  # type: ignore[assignment]  # FRET's forms are never None
            None if f is None else (f[0], _picker(f[1])) for f in self.forms)


_TEMPLATES: dict = {}


def template(scope: str, cond: str, timing: str, n: int | None) -> Template | None:
    """The :class:`Template` of a template key (``n``: the duration in ticks, or None),
    read from its file on first use; None when the key has no file (the caller then
    takes the full build). Keys: ``n`` itself for 0 and 1, one symbolic bound for
    ``n >= 2``."""
    key = (scope, cond, timing, n if n is None or n < 2 else -1)
    t = _TEMPLATES.get(key)
    if t is None:
        try:
            with open(os.path.join(TABLE_DIR, file_name(key)), encoding="utf-8") as fh:
                data = json.load(fh)
        except FileNotFoundError:
            return None
        t = _TEMPLATES[key] = Template(data)
    return t


#: field numbers of the JSON format (:func:`json_format`): the FRET/SMV values (the twelve
#: atoms, the six bounds) first, then the Spot values from _JSON_SPOT on
_JSON_SPOT = 3 * ATOMS + 6

#: per format field (the twelve atoms, then the bounds from BOUND0): the position of its
#: value among a plain requirement's JSON values (the four atoms' FRET/SMV texts, the six
#: bounds, the four atoms' Spot texts), in a FRET/SMV form and in a Spot form
#: (``bytes.translate`` tables: a form's fields are mapped in one call)
_JSON_PLAIN_SMV = bytes(f % ATOMS if f < BOUND0 else ATOMS + f - BOUND0
                        for f in range(BOUND0 + 6)).ljust(256, b"\xff")
_JSON_PLAIN_SPOT = bytes(ATOMS + 6 + f % ATOMS if f < BOUND0 else ATOMS + f - BOUND0
                         for f in range(BOUND0 + 6)).ljust(256, b"\xff")
#: and of a Spot form's fields among any requirement's values (:data:`_JSON_SPOT` on)
_JSON_SPOT_OF = bytes(_JSON_SPOT + f for f in range(BOUND0 + 6)).ljust(256, b"\xff")


def json_format(forms: tuple, enc: Callable[[str], str], seps: tuple) -> tuple | None:
    """``(format, getter, plain getter)`` of the five printed forms ``forms`` (a
    :class:`Template`'s, ``(format, order)`` each, None where Spot has none) as
    JSON strings (``json``'s escaper ``enc``), ft, ft_inf, pt, ft_spot, ft_inf_spot,
    separated by ``seps`` (the four texts between them). ``format`` is a list of the
    escaped literal texts with a slot (None) between each two for a field's value;
    ``getter`` picks, from the values of
    :meth:`fretc.compiler.instantiate.InstantiatedFormalization.json_forms`, each field's value
    in order (``plain getter``: from those of atoms that are the same in ft, ft_inf and
    pt). None when Spot has no form for ft or ft_inf. JSON's escaping maps each character
    on its own, so the escaped text of a filled-in form is its escaped format filled in
    with the escaped values."""
    if any(f is None for f in forms):
        return None
    texts: list = []  # the literal texts between the fields, escaped
    order = bytearray()
    plain = bytearray()
    for i, (fmt, fields) in enumerate(forms):
        if "%%" in fmt:  # a % of the text: the fields found by filling in NULs
            pieces = (enc(fmt) % (("\x00",) * len(fields))).split("\x00")
        else:  # (the usual case: no % in a template's text) every % is a field's
            pieces = enc(fmt).split("%s")
        if i:
            texts[-1] += seps[i - 1] + pieces[0]
            texts += pieces[1:]
        else:
            texts += pieces
        fields = bytes(fields)  # field numbers 0 .. BOUND0 + 5
        if i < 3:
            order += fields
            plain += fields.translate(_JSON_PLAIN_SMV)
        else:
            order += fields.translate(_JSON_SPOT_OF)
            plain += fields.translate(_JSON_PLAIN_SPOT)
    buffer = [None] * (2 * len(texts) - 1)
    buffer[0::2] = texts
    return buffer, _picker(tuple(order)), _picker(tuple(plain))
