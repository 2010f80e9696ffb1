"""Printed formulas by per-template-key instantiation, as FRET's own formalizer does.

:func:`compiler.semantics.formalize` builds the IR of a requirement's ft, ft_inf and pt and
the printers (:mod:`compiler.printers`) walk it. Most of that work depends only on the
requirement's *template key* - scope, condition kind, timing and the duration's class - not
on its atoms (scope mode, condition, stop condition, response). :func:`instantiate` builds,
once per template key, the three formulas with placeholder atoms through the very same
construction (:func:`compiler.semantics.construct`), prints them once (FRET/SMV text of ft,
ft_inf and pt; Spot text of ft and ft_inf) with each placeholder printed as a
:meth:`str.format`-style field ``{i}``, and per requirement only converts and prints the
atoms and fills the cached texts in (one ``%`` formatting per printed formula). The IR itself is built only
when something asks for it (monitors, ``.psl``, ``fretc check``): the returned
:class:`InstantiatedFormalization`'s ``ft``/``ft_inf``/``pt`` run the full build on first use.

**Why the texts are equal.** Every printer is compositional: a node's text is a function of
its operator, bounds and its children's texts, with each compound parenthesized (FRET/SMV:
every binary operation and operator application; Spot: ``!x`` applied to a name or to a
parenthesized compound). So if the IR built from the placeholders is, node for node, the IR
built from the real atoms with the atoms put back, the printed texts are the template texts
with the atom texts put back. The two IRs differ only where a simplifying constructor of
:mod:`compiler.ir` looks inside an argument. It looks at

* the argument's operator: constants fold (``true``/``false``), ``!!a`` is ``a``
  (:func:`~compiler.ir.not_`), ``O FTP``/``O true``, and FRET's since identity
  ``a S (a & FTP) = H a`` (:func:`~compiler.ir.S`);
* equality of two arguments: ``a & a = a``, ``a | a = a``, the since identity's
  ``b.args[0] == a``.

**Fallback rule (opaque-safe atoms).** A placeholder is an atom (``ap``) that equals nothing
but itself. The template is used only when the requirement's atoms are *opaque-safe*, i.e.
every decision the construction took on the placeholders it also takes on the atoms;
otherwise :func:`instantiate` returns the full build (:func:`compiler.semantics.formalize`)
and its printed texts. The atoms are the scope mode, condition, stop condition and response
*of each formula* (ft, ft_inf, pt: temporal functions and FTP expand differently in each, so
the template has twelve atom fields):

1. (operators) *no atom is inspected by a constructor*: none is ``true``, ``false``, a
   negation, ``FTP`` or ``LAST`` at top level, nor a conjunction with ``FTP`` as a side
   (:func:`inspected`). ``not_(!p)`` is ``p``, ``true & x`` is ``x``, ``O FTP`` is ``true``,
   ``p S (p & FTP)`` is ``H p``; a placeholder would fold none of them.
2. (equalities) *every pair the construction compared and found different stays
   different*: while a template is built, :func:`compiler.ir.and_`, :func:`~compiler.ir.or_`
   and :func:`~compiler.ir.S` record each pair of formulas they compared
   (:class:`compiler.ir.recording_comparisons`); each pair is reduced once (:func:`_unify`)
   to the conditions on the atoms under which it would be equal (atom ``f`` equals atom
   ``g``; atom ``f`` equals a template sub-formula; ``n + k`` equals a bound), and a
   requirement whose atoms meet all the conditions of any pair falls back. This catches
   equal atoms (``upon p ... satisfy p``: ``p & !p``-style folds), an atom equal to a
   sub-formula the construction builds from other atoms (a condition ``p | r`` against
   ``or_`` of the response and another atom), and temporal-function expansions equal to structure (``persisted``
   in pt against FRET's ``since`` interval test).

Pairs found equal in the template stay equal with any atoms, and every other branch of the
construction depends on the template key only, so with 1 and 2 the requirement's IR is the
template's IR with the atoms put back, node for node.

The duration shapes the formula through the bounds' comparisons (an empty window ``hi <
lo``, ``hi == 0``): ``within``/``for``/``after`` use bounds from ``n - 1`` to ``n + 1``,
which for every ``n >= 2`` compare alike with each other and with 0. So the template key holds ``n`` itself for ``n``
0 and 1, and one symbolic bound for ``n >= 2``, built with a large sentinel (an ``int``
subclass that keeps its offset through ``+``/``-`` and prints as a format field). Memory is
bounded: there are 432 template keys (8 scopes x 3 condition kinds x (8 timings + 4
duration timings x 3 classes)), about 0.35 ms of CPU each to build. A process builds its
first 4 keys itself; past that it reads the table of all keys (``marshal``, about 0.85 MB,
an index behind a CRC-32, each key's entry behind its own CRC-32, checked and unmarshalled
on its first use: :func:`table_blob`) from fretc's
disk cache (:mod:`common.cache`, entry named by a digest of the construction's sources
and Python's version, :func:`_cache_name`), building and storing it on first use. The table changes
speed only: a cache that is off, unreadable or damaged means the keys are built.

Per requirement the work is kept to the atoms: the leaves of names and literals
(:func:`_name_node`) and the ``Left``/``Right`` endpoints of a scope whose mode is a name
(:func:`_named_endpoints`) are made once per name; a temporal function's expansion is built
once and shared by ft's derived atom and pt (:class:`_SharingExpander`), and ft_inf reuses
ft's atoms unless they call a future-time function; plain atoms are checked against the
template's comparisons reduced once per template (:func:`_plain_conditions`); ``--emit ltl
--json`` takes the five printed forms JSON-escaped in one formatting
(:meth:`InstantiatedFormalization.json_forms`). None of these caches holds a requirement's
expression or text.

Byte identity with the full path is checked by ``tests/compiler/test_instantiate.py`` on
random sentences over the whole grammar, FRET's vectors and the case-study corpus.
"""

from __future__ import annotations

import marshal
import operator
import re
import zlib
import os

from fretish import ast as A

from . import ir
from .expressions import _TIME_NAMES, Expander, SemanticsError, mentions_time
from .ir import FALSE, FTP, LAST, Node, gc_paused
from .printers import _smv, _smv_z, _spot
from .scope_timing import fn_right, pt_endpoints
from .semantics import Formalization, _shape, construct, formalize

__all__ = ["instantiate", "InstantiatedFormalization", "opaque_safe", "template"]

#: format-field numbers: the atoms (mode, condition, stop, response) of ft, of ft_inf and
#: of pt, then the bounds n-2 .. n+3
_FORMULAS = ("ft", "ft_inf", "pt")
_ATOMS = 4
_BOUND0 = 3 * _ATOMS  # field of n + _MIN_OFFSET
_MIN_OFFSET, _MAX_OFFSET = -2, 3
_SENTINEL = 1_000_000_000  # a symbolic n: far from 0 and from every other bound


class _SymbolicBound(int):
    """The duration ``n`` (plus ``offset``) of a template: an ``int`` (the sentinel plus the
    offset) for the constructors' comparisons, printed as the format field of its offset."""

    def __new__(cls, offset: int):
        if not _MIN_OFFSET <= offset <= _MAX_OFFSET:
            raise AssertionError(f"template bound n{offset:+d} out of range")
        self = super().__new__(cls, _SENTINEL + offset)
        self.offset = offset
        return self

    def __add__(self, k):
        if type(k) is int:
            return _SymbolicBound(self.offset + k)
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, k):
        if type(k) is int:
            return _SymbolicBound(self.offset - k)
        return NotImplemented

    def __format__(self, spec: str) -> str:
        return "{%d}" % (_BOUND0 + self.offset - _MIN_OFFSET)

    __str__ = __repr__ = lambda self: self.__format__("")


def _placeholder(field: int) -> Node:
    """An atom standing for format field ``field`` in every printed form."""
    node = Node("ap", name=f"\x00atom{field}")
    node.text = node.ztext = node.stext = "{%d}" % field
    return node


_PLACEHOLDERS = tuple(_placeholder(i) for i in range(3 * _ATOMS))
_FIELD_OF = {id(p): i for i, p in enumerate(_PLACEHOLDERS)}
_FIELD = re.compile(r"\{\d+\}")


class _Template:
    """The printed forms of one template key with fields for the atoms and bounds: ``ft``,
    ``ft_inf``, ``pt`` (FRET/SMV; pt with FTP as ``(Z FALSE)``), ``ft_spot``,
    ``ft_inf_spot`` (Spot, None where Spot cannot print the formula). Each is kept as a
    ``%``-format string and a getter picking its fields' values, in order, from the list
    of the twelve atoms' texts and the bounds (``_BOUND0``). ``compared`` are the pairs of
    template nodes the simplifier found different while building, as conditions on the
    atoms (:func:`_unify`, rule 2), with template nodes as plain tuples (:func:`_data`).
    ``data`` is the whole as plain data (strings, ints, tuples: ``marshal``-able) for
    the disk cache. ``json`` is ``(escaper, separators, compiled)`` of
    :func:`_json_format` and ``plain_compared`` :func:`_plain_conditions`; they and the
    five forms' getters are made on first use (``--emit ltl --json`` reads the forms
    through :func:`_json_format` only)."""

    __slots__ = ("_forms", "compared", "data", "json", "plain_compared")

    def __init__(self, data: tuple):
        self.data = data
        self.json = None
        self.plain_compared = None  # _plain_conditions, made on first use
        self._forms = None  # the five (format, getter), made on first use
        self.compared = data[1]

    def _form(self, i: int):
        forms = self._forms
        if forms is None:
            forms = self._forms = tuple(None if f is None else (f[0], _picker(f[1]))
                                        for f in self.data[0])
        return forms[i]

    ft = property(lambda self: self._form(0))
    ft_inf = property(lambda self: self._form(1))
    pt = property(lambda self: self._form(2))
    ft_spot = property(lambda self: self._form(3))
    ft_inf_spot = property(lambda self: self._form(4))


#: field numbers of the JSON format (:func:`_json_format`): the FRET/SMV values (the twelve
#: atoms, the six bounds) first, then the Spot values from _JSON_SPOT on
_JSON_SPOT = 3 * _ATOMS + 6


#: per format field (the twelve atoms, then the bounds from _BOUND0): the position of its
#: value among a plain requirement's JSON values (:meth:`InstantiatedFormalization.json_forms`:
#: the four atoms' FRET/SMV texts, the six bounds, the four atoms' Spot texts), in a
#: FRET/SMV form and in a Spot form
#: (``bytes.translate`` tables: a form's fields as bytes are mapped in one call, where a
#: ``map`` would make a Python-level call per field, tens of thousands per run)
_JSON_PLAIN_SMV = bytes(f % _ATOMS if f < _BOUND0 else _ATOMS + f - _BOUND0
                        for f in range(_BOUND0 + 6)).ljust(256, b"\xff")
_JSON_PLAIN_SPOT = bytes(_ATOMS + 6 + f % _ATOMS if f < _BOUND0 else _ATOMS + f - _BOUND0
                         for f in range(_BOUND0 + 6)).ljust(256, b"\xff")
#: and of a Spot form's fields among any requirement's values (:data:`_JSON_SPOT` on)
_JSON_SPOT_OF = bytes(_JSON_SPOT + f for f in range(_BOUND0 + 6)).ljust(256, b"\xff")


def _json_format(t: "_Template", enc, seps: tuple):
    """``(format, getter, plain getter)`` of the five printed forms of template ``t`` as
    JSON strings (``json``'s escaper ``enc``), ft, ft_inf, pt, ft_spot, ft_inf_spot,
    separated by ``seps`` (the four texts between them), from the values of
    :meth:`InstantiatedFormalization.json_forms` (``plain getter``: those of atoms that
    are the same in ft, ft_inf and pt, :data:`_JSON_PLAIN_SMV`); None when Spot has no form
    for ft or ft_inf. JSON's escaping maps each character on its own, so the escaped text
    of a filled-in form is its escaped format (``%s`` and ``%%`` escape to themselves, and
    the quotes ``enc`` adds are the JSON string's) filled in with the escaped values."""
    forms = t.data[0]
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
        fields = bytes(fields)  # field numbers 0 .. _BOUND0 + 5
        if i < 3:
            order += fields
            plain += fields.translate(_JSON_PLAIN_SMV)
        else:
            order += fields.translate(_JSON_SPOT_OF)
            plain += fields.translate(_JSON_PLAIN_SPOT)
    buffer = [None] * (2 * len(texts) - 1)
    buffer[0::2] = texts
    return buffer, _picker(tuple(order)), _picker(tuple(plain))


def _picker(order: tuple):
    """``values -> tuple`` of the values at ``order`` (a ``%`` operand)."""
    if not order:
        return lambda values: ()
    if len(order) == 1:
        i = order[0]
        return lambda values: (values[i],)
    return operator.itemgetter(*order)


def build_template(scope: str, cond: str, timing: str, n: int | None) -> tuple:
    """The plain data of :class:`_Template` for one key, built with placeholder atoms by
    :func:`compiler.semantics.construct` (``n``: ticks, or a :class:`_SymbolicBound`)."""
    ph = _PLACEHOLDERS
    sets = [(ph[k + 3], None if cond == "null" else ph[k + 1],
             ph[k + 2] if timing in A.STOP_TIMINGS else None)
            for k in range(0, 3 * _ATOMS, _ATOMS)]
    calls = iter(sets)  # construct converts the fields for ft, ft_inf, pt in order

    def mode(kind: str, last: Node):
        if scope == "null":
            return None
        return ph[2 * _ATOMS] if kind == "pt" else ph[0] if last is LAST else ph[_ATOMS]

    with gc_paused(), ir.recording_comparisons() as compared:
        ft, ft_inf, pt, _, _ = construct(scope, cond, timing, n, mode,
                                         lambda x: next(calls))
    # each pair once (a shared sub-formula is compared again and again), as the
    # conditions on the atoms under which it would be equal
    conditions: dict = {}
    pairs = set()
    for x, y in compared:
        if (id(x), id(y)) in pairs:
            continue
        pairs.add((id(x), id(y)))
        conj: list = []
        if _unify(x, y, conj):
            conditions.setdefault(tuple(conj), None)
    forms = (_compiled(_smv(ft)), _compiled(_smv(ft_inf)), _compiled(_smv_z(pt)),
             _spot_or_none(ft), _spot_or_none(ft_inf))
    return forms, tuple(conditions)


def _data(t: Node):
    """A template node as plain data: its field number for a placeholder, else ``(op,
    name, lo, hi, args)`` with a symbolic bound as ``(offset,)``."""
    f = _FIELD_OF.get(id(t))
    if f is not None:
        return f
    return (t.op, t.name, _bound_data(t.lo), _bound_data(t.hi),
            tuple(_data(a) for a in t.args))


def _bound_data(b):
    return (b.offset,) if type(b) is _SymbolicBound else b


def _compiled(text: str | None):
    """``(format, order)`` of a template text whose fields are ``{i}``: ``format %
    tuple(values[i] for i in order)`` fills them in (None stays None)."""
    if text is None:
        return None
    own = _FIELD.sub("", text)
    if "{" in own or "}" in own or str(_SENTINEL)[:6] in own:
        # a brace of its own, or a bound that lost its offset
        raise AssertionError(f"template text {text!r}")  # pragma: no cover
    order = tuple(int(x[1:-1]) for x in _FIELD.findall(text))
    return _FIELD.sub("%s", text.replace("%", "%%")), order


def _spot_or_none(node: Node):
    try:
        return _compiled(_spot(node))
    except ValueError:
        return None


#: every template key: (scope, condition kind, timing, n class: None, 0, 1 or -1 for >= 2)
ALL_KEYS = tuple(
    (scope, cond, timing, n)
    for scope in ("null", "in", "notin", "onlyIn", "after", "before", "onlyAfter",
                  "onlyBefore")
    for cond in ("null", "regular", "holding")
    for timing in ("null", "immediately", "next", "finally", "eventually", "always",
                   "never", "within", "for", "after", "until", "before")
    for n in ((0, 1, -1) if timing in A.DURATION_TIMINGS else (None,)))

_TEMPLATES: dict = {}
#: keys built directly before the disk table is read: building one takes about 0.3-0.45 ms
#: of CPU, reading the table about 1.3 ms (its name's digest 0.4 ms, the 0.85 MB read 0.8
#: ms) plus about 10 us per key used; so a file of a few keys never reads (nor, on a first
#: run, builds) the table
_BUILT_BEFORE_TABLE = 4
_TABLE: list = []  # [the table (see _table) or None] once the disk cache was consulted


def _build_key(key) -> tuple:
    scope, cond, timing, nkey = key
    return build_template(scope, cond, timing, _SymbolicBound(0) if nkey == -1 else nkey)


def _cache_name() -> str:
    """The disk-cache entry name: a digest of everything the templates are a function of
    (this module and the construction's sources, Python's version for ``marshal``, the
    table's layout :data:`_MAGIC`), the CRC-32 and Adler-32 (``zlib``) of those texts each
    preceded by its length (no OpenSSL or ``pathlib`` to load at start-up; an edit of a
    source changes the name except with odds of about 2**-64; the entry's own CRC-32s guard
    its bytes)."""
    import sys

    here = os.path.dirname(os.path.abspath(__file__))
    crc = adler = 1
    parts = [b"templates-v4", _MAGIC, sys.version.encode()]
    for f in _SOURCES:
        with open(os.path.join(here, f), "rb") as fh:
            parts.append(fh.read())
    for b in parts:
        head = len(b).to_bytes(8, "little")
        crc = zlib.crc32(b, zlib.crc32(head, crc))
        adler = zlib.adler32(b, zlib.adler32(head, adler))
    return "v4-%08x%08x" % (crc, adler)


_SOURCES = ("instantiate.py", "semantics.py", "scope_timing.py", "ir.py", "printers.py",
            "expressions.py")

#: first bytes of a table entry (its layout: :func:`table_blob`)
_MAGIC = b"fretc templates 4\n"


def table_blob(entries) -> bytes:
    """The disk-cache entry of the template table: ``entries`` is one ``marshal``-ed
    :func:`build_template` result per key of :data:`ALL_KEYS`, in that order.

    Layout: :data:`_MAGIC`; the CRC-32 of the index (4 bytes, big-endian); the index's
    length (4 bytes, big-endian); the index, ``marshal.dumps`` of a flat tuple ``(length,
    crc32, length, crc32, ...)``, one pair per key; then the entries one after the other.
    Reading it (:func:`read_table`) checks the index, and each key's entry is checked
    against its own CRC-32 when the key is first used (:func:`template`): a run reads the
    file once and unmarshals only the keys it uses (about 270 of the 432 for a thousand
    varied sentences)."""
    entries = tuple(entries)
    index = marshal.dumps(tuple(x for e in entries for x in (len(e), zlib.crc32(e))))
    return b"".join((_MAGIC, zlib.crc32(index).to_bytes(4, "big"),
                     len(index).to_bytes(4, "big"), index) + entries)


def read_table(blob: bytes) -> dict | None:
    """The table of a disk-cache entry written by :func:`table_blob`: ``{key: (view,
    crc32)}``, ``view`` a ``memoryview`` of the key's ``marshal`` bytes (not yet checked
    against ``crc32``: :func:`template` does, on the key's first use). None when the entry is
    not one (another layout, a damaged header or index, lengths that do not add up to the
    entry's size)."""
    head = len(_MAGIC)
    if len(blob) < head + 8 or not blob.startswith(_MAGIC):
        return None
    crc = int.from_bytes(blob[head:head + 4], "big")
    size = int.from_bytes(blob[head + 4:head + 8], "big")
    view = memoryview(blob)
    index = view[head + 8:head + 8 + size]
    if len(index) != size or zlib.crc32(index) != crc:
        return None
    try:
        pairs = marshal.loads(index)
    except (ValueError, EOFError, TypeError):
        return None
    if type(pairs) is not tuple or len(pairs) != 2 * len(ALL_KEYS):
        return None
    table = {}
    pos = head + 8 + size
    for i, key in enumerate(ALL_KEYS):
        n, c = pairs[2 * i], pairs[2 * i + 1]
        if type(n) is not int or type(c) is not int or n < 0:
            return None
        table[key] = (view[pos:pos + n], c)
        pos += n
    return table if pos == len(blob) else None


def _table() -> dict | None:
    """The table of every key's data (:func:`read_table`) from fretc's disk cache
    (:mod:`common.cache`), built and stored there on first use; None when the disk cache
    is off or fails (keys are then built one by one as needed)."""
    if _TABLE:
        return _TABLE[0]
    from common import cache

    table = None
    try:
        name = _cache_name()
        blob = cache.read_bytes("templates", name)  # None: missing, or the cache is off
        if blob is not None:
            table = read_table(blob)  # None: damaged, built again below
        if table is None and cache.cache_dir() is not None:
            blob = table_blob(marshal.dumps(_build_key(k)) for k in ALL_KEYS)
            cache.write_bytes("templates", name, blob)
            table = read_table(blob)
    except OSError:
        table = None
    _TABLE.append(table)
    return table


def _from_table(table: dict, key) -> tuple | None:
    """The data of ``key`` from the disk table, or None when its entry fails its CRC-32 or
    does not unmarshal: the key is then built, and the damaged cache entry removed so the
    next run that needs the table writes it again."""
    view, crc = table[key]
    if zlib.crc32(view) == crc:
        try:
            data = marshal.loads(view)
        except (ValueError, EOFError, TypeError):
            data = None
        if type(data) is tuple:
            return data
    from common import cache

    try:
        cache.remove("templates", _cache_name())
    except OSError:  # the sources cannot be read for the name
        pass
    return None


def template(scope: str, cond: str, timing: str, n: int | None) -> _Template:
    """The cached :class:`_Template` of a template key (``n``: the duration in ticks, or
    None). Keys: ``n`` itself for 0 and 1, one symbolic bound for ``n >= 2``. The first
    :data:`_BUILT_BEFORE_TABLE` keys of a process are built, the others read from the disk
    table (:func:`_table`), or built when it is off or the key's entry is damaged."""
    nkey = n if n is None or n < 2 else -1
    key = (scope, cond, timing, nkey)
    t = _TEMPLATES.get(key)
    if t is None:
        table = _table() if len(_TEMPLATES) >= _BUILT_BEFORE_TABLE else None
        data = None if table is None else _from_table(table, key)
        t = _TEMPLATES[key] = _Template(data if data is not None else _build_key(key))
    return t


#: operators a simplifying constructor of compiler.ir looks for in an argument
_INSPECTED_OPS = frozenset(("true", "false", "!", "FTP", "LAST"))


def inspected(atom: Node) -> bool:
    """Rule 1: would a simplifying constructor look inside ``atom`` (a constant, a
    negation, FTP or LAST at top level, or a conjunction with FTP as a side, FRET's since
    identity)?"""
    op = atom.op
    return op in _INSPECTED_OPS or (op == "&" and (atom.args[0].op == "FTP"
                                                   or atom.args[1].op == "FTP"))


def _unify(x: Node, y: Node, out: list) -> bool:
    """Could template nodes ``x`` and ``y`` be equal once the placeholders are replaced by
    atoms and the symbolic bounds by ``n`` plus their offsets? False: never; True: exactly
    when every condition appended to ``out`` holds: ``(0, f, g)`` atom ``f`` equals atom
    ``g``, ``(1, f, t)`` atom ``f`` equals template node ``t`` instantiated, ``(2, k, v)``
    ``n + k == v``."""
    if x is y:
        return True
    fx, fy = _FIELD_OF.get(id(x)), _FIELD_OF.get(id(y))
    if fx is not None and fy is not None:
        out.append((0, fx, fy))
        return True
    if fx is not None or fy is not None:
        out.append((1, fx, _data(y)) if fx is not None else (1, fy, _data(x)))
        return True
    if x.op != y.op or x.name != y.name or len(x.args) != len(y.args):
        return False
    for bx, by in ((x.lo, y.lo), (x.hi, y.hi)):
        sx, sy = type(bx) is _SymbolicBound, type(by) is _SymbolicBound
        if sx and sy:
            if bx.offset != by.offset:
                return False
        elif sx or sy:
            if (bx if sx else by) is None or (by if sx else bx) is None:
                return False
            out.append((2, bx.offset, by) if sx else (2, by.offset, bx))
        elif bx != by:
            return False
    return all(_unify(a, b, out) for a, b in zip(x.args, y.args))


def _matches(real: Node, t, atoms, n) -> bool:
    """Is the requirement's node ``real`` equal to template node ``t`` (as
    :func:`_data`) instantiated?"""
    if real is None:
        return False
    if type(t) is int:
        return real == atoms[t]
    op, name, lo, hi, args = t
    if (real.op != op or real.name != name or len(real.args) != len(args)
            or real.lo != _bound(lo, n) or real.hi != _bound(hi, n)):
        return False
    return all(_matches(a, b, atoms, n) for a, b in zip(real.args, args))


def _bound(b, n):
    if type(b) is tuple:
        return n + b[0]
    return b


def opaque_safe(tmpl: "_Template", atoms, n: int | None) -> bool:
    """Rules 1 and 2 of the module docstring: no atom is inspected by a constructor
    (:func:`inspected`), and every pair of formulas the template's construction compared
    and found different is still different with the requirement's atoms (``atoms``: the
    twelve atoms by field, None where absent; ``n`` the duration in ticks)."""
    for a in atoms:
        if a is not None and inspected(a):
            return False
    return _compared_safe(tmpl, atoms, n)


def _compared_safe(tmpl: "_Template", atoms, n: int | None) -> bool:
    """Rule 2 of :func:`opaque_safe` alone."""
    for conj in tmpl.compared:
        for kind, f, v in conj:
            if kind == 0:
                if atoms[f] != atoms[v]:
                    break
            elif kind == 1:
                if not _matches(atoms[f], v, atoms, n):
                    break
            elif n + f != v:
                break
        else:
            return False  # this pair of the template is equal with these atoms
    return True


def _plain_conditions(tmpl: "_Template") -> tuple:
    """``tmpl.compared`` for atoms that are the same in ft, ft_inf and pt (field ``f`` is
    field ``f % 4``): a condition "atom f equals atom g" of two fields of the same
    expression always holds and is dropped, equal conjunctions are kept once, and each
    conjunction checks the bounds, then atom equalities, then the structural matches
    (cheapest first; the order does not change the result)."""
    conds = tmpl.plain_compared
    if conds is None:
        out: dict = {}
        for conj in tmpl.compared:
            kept = []
            for kind, f, v in conj:
                if kind == 0:
                    f, v = f % _ATOMS, v % _ATOMS
                    if f == v:
                        continue
                elif kind == 1:
                    f %= _ATOMS
                kept.append((kind, f, v))
            kept.sort(key=lambda c: (2, 0, 1)[c[0]])
            out.setdefault(tuple(kept), None)
        conds = tmpl.plain_compared = tuple(out)
    return conds


def _plain_compared_safe(tmpl: "_Template", one, atoms, n: int | None) -> bool:
    """:func:`_compared_safe` for plain atoms: ``one`` the four atoms (mode, condition,
    stop, response), ``atoms`` them three times (ft, ft_inf, pt)."""
    for conj in _plain_conditions(tmpl):
        for kind, f, v in conj:
            if kind == 0:
                if one[f] != one[v]:
                    break
            elif kind == 1:
                a = one[f]
                if a is None or a.op != v[0] or not _matches(a, v, atoms, n):
                    break
            elif n + f != v:
                break
        else:
            return False  # this pair of the template is equal with these atoms
    return True


class _Timed(Exception):
    """Raised by :class:`_PlainExpander` at the first temporal function or FTP."""


_TIMED = object()  # an expression with temporal functions or FTP (converted per formula)


class _PlainExpander(Expander):
    """:class:`~compiler.expressions.Expander` for ft (``FTP``, ``LAST``) that converts an
    expression *without* temporal functions or FTP - which then means the same in ft,
    ft_inf and pt (:mod:`compiler.semantics` converts it once) - and collects its
    variables on the way: ``names`` holds the ``ap``/``var`` names in the order the
    conversion creates them, which is the pre-order of the IR it returns (children are
    converted left to right, nothing converted is dropped: ``!!a`` folds to ``a``, which
    keeps ``a``'s names), i.e. :func:`compiler.ir.variables` of the result. At a temporal
    function or FTP it raises :class:`_Timed` (the caller converts per formula), so one
    walk replaces :func:`~compiler.expressions.mentions_time`'s scan and the conversion."""

    def __init__(self):
        super().__init__("ft", FTP, LAST)
        self.names: dict = {}

    # The common shapes (names, comparisons, and/or/implies/xor/iff, negation, literals,
    # arithmetic) are dispatched on the AST node's exact type and build the nodes
    # Expander builds for them, in the same order (children left to right); any other
    # shape, or an error, is Expander's own code.
    def bool(self, e: A.Expr) -> Node:
        t = type(e)
        if t is _Var:
            return self._name(e.name, "ap")
        if t is _Binary:
            op = e.op
            if op in _COMPARISON_OPS:  # Expander: ir.cmp, no derived atom (no preReal here)
                return Node("cmp", (self.term(e.left), self.term(e.right)), name=op)
            if op in _BOOL_OPS:  # Expander: Node(op) for & | ->, ir.xor, ir.iff
                return Node(op, (self.bool(e.left), self.bool(e.right)))
        elif t is _Unary and e.op == "!":
            return ir.not_(self.bool(e.operand))
        return Expander.bool(self, e)

    def _name(self, name: str, op: str) -> Node:
        """The leaf ``op`` (``ap`` or ``var``) of variable ``name``, recorded in
        :attr:`names`; FTP raises :class:`_Timed`."""
        if name == "FTP":
            raise _Timed
        self.names[name] = None
        return _name_node(op, name)

    def _atom(self, node: Node) -> Node:
        return node  # no preInt/preReal here (they raise _Timed): never a derived atom

    def _bool_call(self, e: A.Call) -> Node:
        if e.name in _TIME_NAMES:
            raise _Timed
        return Expander._bool_call(self, e)

    def term(self, e: A.Expr) -> Node:
        t = type(e)
        if t is _Var:
            return self._name(e.name, "var")
        if t is _NumLit:
            return _name_node("num", e.text)  # ir.num
        if t is _Binary and e.op in _ARITH_OPS:  # ir.arith
            return Node("arith", (self.term(e.left), self.term(e.right)), name=e.op)
        if isinstance(e, A.Call) and e.name in _TIME_NAMES:
            raise _Timed  # preInt, preReal
        return Expander.term(self, e)


_Var, _Binary, _Unary, _NumLit = A.Var, A.Binary, A.Unary, A.NumLit
_COMPARISON_OPS = frozenset(A.COMPARISON_OPS)
_BOOL_OPS = frozenset(A.BOOL_OPS)
_ARITH_OPS = frozenset(A.ARITH_OPS)

#: the leaf nodes of names and literals made so far: ``(op, name) -> Node`` for ``ap``,
#: ``var`` and ``num``; a node is immutable and its printed texts (memo slots of
#: compiler.printers) depend on its op and name only, so one node serves every
#: requirement that mentions the name. Emptied when it reaches _LEAVES_MAX entries.
_LEAVES: dict = {}
_LEAVES_MAX = 65536


#: (scope, mode name or None) -> (Left, Right, Right of ft_inf) of the temporal functions
#: for a scope whose mode is a plain name (or the null scope): made once per name, emptied
#: with _LEAVES
_ENDPOINTS: dict = {}


def _named_endpoints(scope: str, m: Node | None) -> tuple:
    """``(Left, Right, Right_inf)``: :func:`~compiler.scope_timing.pt_endpoints`'s left of
    ``m``, :func:`~compiler.scope_timing.fn_right` of ``m`` with ``LAST`` and with FALSE;
    ``m`` is None or a leaf of :data:`_LEAVES` (a name), whose endpoints are functions of
    the scope and the name only: made once per pair (:data:`_ENDPOINTS`)."""
    key = (scope, None if m is None else m.name)
    ends = _ENDPOINTS.get(key)
    if ends is None:
        ends = _ENDPOINTS[key] = (pt_endpoints(scope, m)[0], fn_right(scope, m, LAST),
                                  fn_right(scope, m, FALSE))
    return ends


def _name_node(op: str, name: str) -> Node:
    """The leaf ``Node(op, name=name)`` (``ap``, ``var`` or ``num``), made once per
    ``(op, name)`` (:data:`_LEAVES`)."""
    key = (op, name)
    node = _LEAVES.get(key)
    if node is None:
        if len(_LEAVES) >= _LEAVES_MAX:
            _LEAVES.clear()
            _ENDPOINTS.clear()
        node = _LEAVES[key] = Node(op, name=name)
    return node


class _SharingExpander(Expander):
    """:class:`~compiler.expressions.Expander` whose temporal functions' expansions are
    shared, through ``memo``, by the expanders of one requirement: an expansion is built
    in a pt expander whatever the formula kind, from the call, ``Left``, ``Right`` and
    the endpoint-free flag only (:meth:`Expander._past_function`), so ft's derived
    ``past`` atom holds pt's expansion of the same call, and pt's derived ``future`` atom
    ft's. Keyed by the identities of the call and of the endpoints (alive while the
    requirement is instantiated); the nodes are equal to those built anew, and shared
    nodes are immutable."""

    def __init__(self, kind: str, left_pt: Node, right_ft: Node, memo: dict):
        super().__init__(kind, left_pt, right_ft)
        self.memo = memo

    # the common shapes as in _PlainExpander (same nodes, same order; leaves shared)
    def bool(self, e: A.Expr) -> Node:
        t = type(e)
        if t is _Var:
            name = e.name
            return FTP if name == "FTP" else _name_node("ap", name)
        if t is _Binary:
            op = e.op
            if op in _COMPARISON_OPS:
                return self._atom(Node("cmp", (self.term(e.left), self.term(e.right)),
                                       name=op))
            if op in _BOOL_OPS:
                return Node(op, (self.bool(e.left), self.bool(e.right)))
        elif t is _Unary and e.op == "!":
            return ir.not_(self.bool(e.operand))
        return Expander.bool(self, e)

    def term(self, e: A.Expr) -> Node:
        t = type(e)
        if t is _Var:
            return _name_node("var", e.name)  # ir.var
        if t is _NumLit:
            return _name_node("num", e.text)  # ir.num
        if t is _Binary and e.op in _ARITH_OPS:  # ir.arith
            return Node("arith", (self.term(e.left), self.term(e.right)), name=e.op)
        return Expander.term(self, e)

    def _past_function(self, e: A.Call) -> Node:
        key = (0, id(e), id(self.left_pt), id(self.right_ft), self.free)
        node = self.memo.get(key)
        if node is None:
            node = self.memo[key] = Expander._past_function(self, e)
        return node

    def _future_function(self, e: A.Call) -> Node:
        key = (1, id(e), id(self.left_pt), id(self.right_ft), self.free)
        node = self.memo.get(key)
        if node is None:
            node = self.memo[key] = Expander._future_function(self, e)
        return node


#: FRET's future-time functions (compiler.expressions' ``_FUTURE_FUNCS``, checked by
#: tests/compiler/test_instantiate.py)
_FUTURE_FUNCTIONS = frozenset(("persists", "occurs", "nextOcc"))


def _has_future_function(e: A.Expr) -> bool:
    """Does ``e`` call a future-time function (``persists``, ``occurs``, ``nextOcc``)
    anywhere?"""
    for x in A.walk(e):
        if isinstance(x, A.Call) and x.name in _FUTURE_FUNCTIONS:
            return True
    return False


def _variables_into(node: Node, seen: dict, done: set) -> None:
    """:func:`compiler.ir.variables` of ``node`` added to ``seen`` (a dict used as an
    ordered set), in the same order: pre-order, first appearance; a sub-formula met again
    (``done``: node identities) is skipped, its names are in ``seen`` already."""
    op = node.op
    if op == "ap" or op == "var":
        seen[node.name] = None
        return
    for a in node.args:
        if a.args:
            i = id(a)
            if i in done:
                continue
            done.add(i)
            _variables_into(a, seen, done)
        elif a.op == "ap" or a.op == "var":
            seen[a.name] = None


_BOUND_TEXTS: dict = {None: [None] * (_MAX_OFFSET - _MIN_OFFSET + 1)}


def _bound_texts(n: int | None) -> list:
    """The texts of the bounds ``n - 2 .. n + 3`` (the format fields from ``_BOUND0``; None
    for no duration), made once per ``n`` (at most 4096 kept)."""
    texts = _BOUND_TEXTS.get(n)
    if texts is None:
        if len(_BOUND_TEXTS) > 4096:
            _BOUND_TEXTS.clear()
            _BOUND_TEXTS[None] = [None] * (_MAX_OFFSET - _MIN_OFFSET + 1)
        texts = _BOUND_TEXTS[n] = [str(n + k) for k in range(_MIN_OFFSET, _MAX_OFFSET + 1)]
    return texts


class InstantiatedFormalization(Formalization):
    """A :class:`~compiler.semantics.Formalization` whose printed formulas come from a
    template; ``ft``, ``ft_inf`` and ``pt`` are built (the full construction) on first use.
    :meth:`smv` and :meth:`spot` give the texts.

    ``atoms`` are the ``(mode, condition, stop, response)`` IR atoms of ft, of ft_inf and
    of pt, in one tuple of twelve (None where absent); ``texts`` their printed texts
    (FRET/SMV; pt's with FTP as ``(Z FALSE)``)."""

    def __init__(self, req: A.Requirement, tick_period: Fraction | None, tmpl: _Template,
                 atoms: tuple, texts: list, variables: list, warnings: list,
                 ticks: int | None, pt_causal: bool, plain: bool = False):
        self.key = req.key
        self.variables = variables
        self.warnings = warnings
        self.ticks = ticks
        self.pt_causal = pt_causal
        self._req, self._period, self._tmpl = req, tick_period, tmpl
        self._atoms, self._texts = atoms, texts
        self._full = None
        self._smv_values = None
        self._plain = plain  # the same four atoms in ft, ft_inf and pt
        self._spot_values = None

    def _build(self) -> Formalization:
        f = self._full
        if f is None:
            f = self._full = formalize(self._req, self._period)
        return f

    def __reduce__(self):
        """Pickled (a plan shipped to workers) as the full build it stands for: the texts
        the printers give on it are the template's (module docstring)."""
        f = self._build()
        return (Formalization, (f.key, f.ft, f.ft_inf, f.pt, f.variables, f.warnings,
                                f.ticks, f.pt_causal))

    ft = property(lambda self: self._build().ft, doc="ft (IR), built on first use")
    ft_inf = property(lambda self: self._build().ft_inf,
                      doc="ft_inf (IR), built on first use")
    pt = property(lambda self: self._build().pt, doc="pt (IR), built on first use")

    def _values(self, texts) -> list:
        n = self.ticks
        if n is None:
            return texts
        return list(texts) + _bound_texts(n)

    def smv(self, which: str) -> str:
        """FRET/SMV text of ``ft``, ``ft_inf`` or ``pt`` (pt with FTP as ``(Z FALSE)``)."""
        fmt, pick = getattr(self._tmpl, which)
        values = self._smv_values
        if values is None:
            values = self._smv_values = self._values(self._texts)
        return fmt % pick(values)

    def printed(self) -> tuple:
        """``(ft, ft_inf, pt, ft_spot, ft_inf_spot)``: :meth:`smv` of the three formulas
        and :meth:`spot` of ft and ft_inf, in that order (the atoms' values picked once)."""
        t = self._tmpl
        values = self._smv_values
        if values is None:
            values = self._smv_values = self._values(self._texts)
        fmt, pick = t.ft
        ft = fmt % pick(values)
        fmt, pick = t.ft_inf
        ft_inf = fmt % pick(values)
        fmt, pick = t.pt
        return ft, ft_inf, fmt % pick(values), self.spot("ft"), self.spot("ft_inf")

    def json_forms(self, enc, seps: tuple) -> str | None:
        """The five printed forms (as :meth:`printed`) as JSON strings escaped by ``enc``
        (``json``'s ``encode_basestring_ascii``), separated by ``seps`` (the four texts
        between them): one ``%`` formatting of the template's escaped forms
        (:func:`_json_format`) with the atoms' escaped texts. None where :meth:`printed`
        would raise (Spot has no form) - the caller then takes :meth:`printed`'s path."""
        t = self._tmpl
        j = t.json
        if j is None or j[0] is not enc or j[1] != seps:
            j = t.json = (enc, seps, _json_format(t, enc, seps))
        compiled = j[2]
        if compiled is None:
            return None
        buffer, pick, pick_plain = compiled
        atoms = self._atoms
        texts = self._texts
        bounds = _bound_texts(self.ticks)
        try:
            if self._plain:  # one atom set: _JSON_PLAIN_SMV's values
                values = [None if x is None else enc(x)[1:-1] for x in texts[:_ATOMS]]
                values += bounds
                values += [None if a is None else enc(_spot(a))[1:-1] for a in atoms[:_ATOMS]]
                pick = pick_plain
            else:  # Spot forms: ft's and ft_inf's atoms only (pt's have past operators)
                values = [None if x is None else enc(x)[1:-1] for x in texts]
                values += bounds
                values += [None if a is None else enc(_spot(a))[1:-1]
                           for a in atoms[:2 * _ATOMS]]
                values += (None,) * _ATOMS
                values += bounds
        except ValueError:
            return None
        buffer = buffer.copy()
        buffer[1::2] = pick(values)
        return "".join(buffer)

    def spot(self, which: str) -> str:
        """Spot text of ``ft`` or ``ft_inf``; ``ValueError`` where Spot has no form."""
        compiled = getattr(self._tmpl, which + "_spot")
        if compiled is None:
            return _spot(getattr(self, which))  # raises the printer's own error
        fmt, pick = compiled
        if self._plain:
            # one atom set, whose Spot texts serve ft and ft_inf (pt's fields, never picked
            # by a Spot form, hold the same texts)
            values = self._spot_values
            if values is None:
                one = [None if a is None else _spot(a) for a in self._atoms[:_ATOMS]]
                values = self._spot_values = self._values(one * 3)
            return fmt % pick(values)
        lo = 0 if which == "ft" else _ATOMS  # only that formula's atoms: pt's have past
        texts = [None] * (3 * _ATOMS)
        for i in range(lo, lo + _ATOMS):
            a = self._atoms[i]
            if a is not None:
                texts[i] = _spot(a)
        return fmt % pick(self._values(texts))


from gc import isenabled as _gc_isenabled  # noqa: E402 (used by instantiate only)


def instantiate(req: A.Requirement, tick_period: Fraction | None = None) -> Formalization:
    """:func:`compiler.semantics.formalize` for printing: an
    :class:`InstantiatedFormalization` when the requirement's atoms are opaque-safe (module
    docstring), else the full build. Same errors, warnings, variables and ticks as
    :func:`formalize`; the printed texts (:func:`formula_text`) are byte-identical to the
    printers' on the full build."""
    if not _gc_isenabled():  # paused already (compile_entries, --emit ltl): no context
        return _instantiate(req, tick_period)
    with gc_paused():
        return _instantiate(req, tick_period)


def _instantiate(req: A.Requirement, tick_period: Fraction | None) -> Formalization:
    """:func:`instantiate`'s work, the cyclic garbage collector paused."""
    scope, cond, timing, n, warnings = _shape(req, tick_period)
    mode = req.scope.mode if scope != "null" else None
    cexpr = req.condition.expr if cond != "null" else None
    sexpr = req.timing.stop if timing in A.STOP_TIMINGS else None
    exprs = (mode, cexpr, sexpr, req.response)
    # An expression without temporal functions or FTP converts to the same atom in ft,
    # ft_inf and pt (Expander's kind, endpoints and endpoint-free forms only shape
    # temporal functions; compiler.semantics converts it once) and prints alike in pt
    # (no FTP): converted and printed once, its variables collected on the way.
    x = _PlainExpander()
    one: list = []  # per expression: its atom, None (absent) or _TIMED
    names: list = []  # per expression: its variables (a dict), None for _TIMED
    try:
        for e in exprs:
            if e is None:
                one.append(None)
                names.append({})
                continue
            x.names = {}
            try:
                one.append(x.bool(e))
                names.append(x.names)
            except _Timed:
                one.append(_TIMED)
                names.append(None)
    except SemanticsError:
        if not any(e is not None and mentions_time(e) for e in exprs):
            raise  # the error of the one conversion (Expander("ft", FTP, LAST))
        # the per-formula conversion raises, in its own order (mode, then per formula)
        one = [_TIMED if e is not None else None for e in exprs]
        names = [None] * 4
    # (identity tests: ``in`` would call Node.__eq__ on each atom)
    if one[0] is not _TIMED and one[1] is not _TIMED and one[2] is not _TIMED \
            and one[3] is not _TIMED:
        for a in one:
            if a is not None and (a.op in _INSPECTED_OPS or a.op == "&") and inspected(a):
                return formalize(req, tick_period)
        tmpl = template(scope, cond, timing, n)
        atoms = tuple(one) * 3
        if not _plain_compared_safe(tmpl, one, atoms, n):
            return formalize(req, tick_period)
        texts = [None if a is None else _smv(a) for a in one] * 3
        variables = {}
        for d in names:
            variables.update(d)
        # variables in sentence order: mode, condition, stop, response
        return InstantiatedFormalization(req, tick_period, tmpl, atoms, texts,
                                         list(variables), warnings, n, True, plain=True)
    # the atoms of each formula, converted as compiler.semantics.construct does (the
    # expressions with temporal functions; the others are the same in every formula)
    m = one[0]
    if m is _TIMED:
        m_pt = Expander("pt", FTP, LAST, free=True).bool(mode)
        # the endpoint-free forms never read the endpoints: ft_inf's mode is ft's
        m_ft = m_inf = Expander("ft", FTP, LAST, free=True).bool(mode)
    else:
        m_pt = m_ft = m_inf = m
    if m is None or m is not _TIMED and m.op == "ap" and _LEAVES.get(("ap", m.name)) is m:
        left, right, right_inf = _named_endpoints(scope, m)
    else:
        left, _ = pt_endpoints(scope, m_pt)
        right = fn_right(scope, m_ft, LAST)
        right_inf = fn_right(scope, m_inf, FALSE)
    memo: dict = {}
    px = _SharingExpander("pt", left, right, memo)
    fx = _SharingExpander("ft", left, right, memo)
    ix = _SharingExpander("ft", left, right_inf, memo)
    rest = tuple(zip(exprs[1:], one[1:]))
    a_ft = tuple(fx.bool(e) if a is _TIMED else a for e, a in rest)
    # ft_inf differs from ft only in Right (LAST or FALSE), which only a future-time
    # function's expansion reads: without one, ft_inf's atom is ft's
    a_inf = tuple(ix.bool(e) if a is _TIMED and _has_future_function(e) else f
                  for (e, a), f in zip(rest, a_ft))
    atoms = (m_ft, *a_ft, m_inf, *a_inf,
             m_pt, *(px.bool(e) if a is _TIMED else a for e, a in rest))
    plain_text = [None if a is None or a is _TIMED else _smv(a) for a in one]
    texts = []
    for i, a in enumerate(atoms):
        t = plain_text[i % _ATOMS]
        if t is None and a is not None:
            t = _smv_z(a) if i >= 2 * _ATOMS else _smv(a)
        texts.append(t)
    pt_causal = not px.has_future_atom
    tmpl = template(scope, cond, timing, n)
    if not opaque_safe(tmpl, atoms, n):
        return formalize(req, tick_period)
    # variables in sentence order: mode, condition, stop, response (of ft)
    variables = {}
    # Left and Right are made of the mode's names, which come first: not walked
    done = {id(left), id(right), id(right_inf)}
    for a, d in zip(atoms[:_ATOMS], names):
        if d is None:
            _variables_into(a, variables, done)
        else:
            variables.update(d)
    return InstantiatedFormalization(req, tick_period, tmpl, atoms, texts,
                                     list(variables), warnings, n, pt_causal)


def formula_text(f: Formalization, which: str) -> str:
    """Printed form ``which`` of a formalization: ``ft``, ``ft_inf``, ``pt`` (FRET/SMV) or
    ``ft_spot``, ``ft_inf_spot`` (Spot), from the template when there is one."""
    if which.endswith("_spot"):
        base = which[:-5]
        if isinstance(f, InstantiatedFormalization):
            return f.spot(base)
        return _spot(getattr(f, base))
    if isinstance(f, InstantiatedFormalization):
        return f.smv(which)
    return _smv_z(f.pt) if which == "pt" else _smv(getattr(f, which))
