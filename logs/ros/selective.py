"""Selective decoding: decode only the message fields the signal bindings read.

Design notes: ARCHITECTURE.md, `logs/ros/selective.py`."""

from __future__ import annotations

import struct
import sys
from collections.abc import Callable, Iterable
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.common.streams import base_topic

if TYPE_CHECKING:
    from fretc.logs.base import LogSource
    from rosbags.typesys.store import Typestore

__all__ = ["selective_decoder", "wanted_fields", "install", "stats", "HEADER_STAMP"]

#: Field paths as in :class:`fretc.signals.bindings.Field`: attribute names and indexes.
Path = tuple[Any, ...]

_SIZE = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
         "int32": 4, "uint32": 4, "int64": 8, "uint64": 8, "float32": 4, "float64": 8}
_FMT = {"bool": "?", "byte": "B", "char": "B", "int8": "b", "uint8": "B", "int16": "h",
        "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
        "float32": "f", "float64": "d"}
_NP = {"bool": "bool_", "char": "uint8", "byte": "byte"}
_HEADER = "std_msgs/msg/Header"
_LASER = "sensor_msgs/msg/LaserScan"
_U32 = struct.Struct("<I").unpack_from
#: A path asking for ``header.stamp`` if the type has a std_msgs/Header (for the header
#: time base); without it a selectively decoded message has ``header_stamp`` None.
HEADER_STAMP: Path = ("\0header.stamp",)
#: Decoders built and messages decoded by each path (for tests and benchmarks).
stats = {"fast_types": 0, "full_types": 0, "fallback_messages": 0}


class _NotCovered(Exception):
    """The fast path does not cover this (type, fields): use the full decoder."""


def wanted_fields(bindings: Any) -> dict[str, frozenset[Path]]:  # a signals Bindings
    """Topic -> field paths the variables of ``bindings`` read (``/scan.ranges`` gives
    ``("ranges",)``); the tick topic and topics read only by ``age()`` get an empty set;
    with the header time base every topic also gets :data:`HEADER_STAMP`."""
    out: dict[str, set] = {base_topic(t): set() for t in bindings.topics}
    if bindings.tick.topic is not None:
        out.setdefault(bindings.tick.topic, set())
    for b in bindings.variables.values():
        for f in b.fields:  # a stream's fields and filtered fields are its topic's
            paths = out.setdefault(base_topic(f.topic), set())
            paths.add(tuple(f.path))
            paths.update(tuple(flt.path) for flt in getattr(f, "filters", ()))
    if bindings.time_base != "log":  # the clock reads header.stamp of every message
        for paths in out.values():
            paths.add(HEADER_STAMP)
    return {t: frozenset(p) for t, p in out.items()}


def install(source: LogSource, bindings: Any) -> None:  # a signals Bindings or None
    """Make ``source`` decode only the fields ``bindings`` read (None: everything). Its
    cached decoders are dropped when the wanted fields change."""
    fields = wanted_fields(bindings) if bindings is not None else None
    if getattr(source, "_wanted_fields", None) != fields:
        try:
            source._wanted_fields = fields
        except AttributeError:  # a source that cannot take it decodes in full
            return
        cache = getattr(source, "_decoders", None)
        if cache:  # keep the None entries: unreadable schemas, already reported
            for key in [k for k, v in cache.items() if v is not None]:
                del cache[key]


# --------------------------------------------------------------------------- tree of fields
def _tree(store, typename: str, paths) -> dict:
    """Nested dict: field name -> sub-dict (fields of a nested message) or None (the whole
    value). :data:`HEADER_STAMP` asks for ``header.stamp`` when the type has a
    std_msgs/Header (``Message.header_stamp`` is None without it); beside a LaserScan's
    ``ranges``, ``range_min``/``range_max`` (REP 117 filtering)."""
    fields = dict(store.get_msgdef(typename).fields)
    tree: dict = {}
    all_paths = [p for p in paths if p != HEADER_STAMP]
    if (HEADER_STAMP in paths and "header" in fields and fields["header"][0] == 2
            and fields["header"][1] == _HEADER):
        all_paths += [("header", "stamp", "sec"), ("header", "stamp", "nanosec")]
    for path in all_paths:
        _add(store, typename, tree, tuple(path))
    return tree


def _add(store, typename: str, tree: dict, path: Path) -> None:
    if not path:
        raise _NotCovered("a whole message is wanted")
    name = path[0]
    if not isinstance(name, str):
        raise _NotCovered("an index into a message")
    fields = dict(store.get_msgdef(typename).fields)
    if name not in fields:
        raise _NotCovered(f"{typename} has no field {name!r}")
    desc = fields[name]
    kind = desc[0]
    rest = path[1:]
    if typename == _LASER and name == "ranges":
        tree.setdefault("range_min", None)
        tree.setdefault("range_max", None)
    if kind == 2 and rest and isinstance(rest[0], str):  # NAME: a nested message
        sub = tree.get(name)
        if name in tree and sub is None:
            return
        if sub is None:
            sub = tree[name] = {}
        _add(store, desc[1], sub, rest)
        return
    if kind == 2:
        raise _NotCovered("a whole nested message is wanted")
    if kind in (3, 4) and _elem(desc)[0] == 2:
        raise _NotCovered("an array of messages is wanted")
    tree[name] = None  # primitive, string or array: read whole (indexes applied later)


def _elem(desc):
    return desc[1][0]


# --------------------------------------------------------------------------- code generation
class _Gen:
    """Emits the body of one decoder (``pos`` relative to the data start, ``base`` added to
    every read: 4 for CDR's encapsulation header, 0 for ROS 1)."""

    def __init__(self, store, cdr: bool) -> None:
        self.store = store
        self.cdr = cdr
        self.base = 4 if cdr else 0
        self.lines: list[str] = []
        self.env: dict[str, Any] = {"np": np, "_u32": _U32}
        self.off = 0  # constant offset not yet added to pos
        self.known = 8  # pos is a multiple of this
        self.n = 0
        self.pending: list[tuple[int, str, str]] = []

    def name(self, prefix: str) -> str:
        self.n += 1
        return f"{prefix}{self.n}"

    def emit(self, ind: int, text: str) -> None:
        self.lines.append("    " * ind + text)

    def at(self) -> str:
        k = self.off + self.base
        return f"pos + {k}" if k else "pos"

    def read(self, t: str, target: str) -> None:
        """Read primitive ``t`` at the current offset into ``target``; reads at constant
        offsets from ``pos`` are gathered into one ``struct`` call (:meth:`emit_reads`)."""
        self.pending.append((self.off + self.base, t, target))

    def emit_reads(self, ind: int) -> None:
        if not self.pending:
            return
        reads = sorted(self.pending)
        self.pending = []
        start = reads[0][0]
        fmt, at = "<", start
        for o, t, _ in reads:
            fmt += "x" * (o - at) + _FMT[t]
            at = o + _SIZE[t]
        key = self.name("_S")
        self.env[key] = struct.Struct(fmt).unpack_from
        names = ", ".join(target for _, _, target in reads)
        where = f"pos + {start}" if start else "pos"
        self.emit(ind, f"{names}{',' if len(reads) == 1 else ''} = {key}(raw, {where})")

    def flush(self, ind: int) -> None:
        self.emit_reads(ind)
        if self.off:
            self.emit(ind, f"pos += {self.off}")
            low = self.off & -self.off
            self.known = min(self.known, low)
            self.off = 0

    def align(self, a: int, ind: int) -> None:
        if not self.cdr or a <= 1:
            return
        if a <= self.known:
            self.off = (self.off + a - 1) & -a
            return
        self.flush(ind)
        self.emit(ind, f"pos = (pos + {a - 1}) & -{a}")
        self.known = a

    def alignment(self, desc) -> int:
        kind = desc[0]
        if kind == 1:
            return 4 if desc[1][0] == "string" else _SIZE[desc[1][0]]
        if kind == 2:
            fields = self.store.get_msgdef(desc[1]).fields
            return self.alignment(fields[0][1]) if fields else 1
        if kind == 3:
            return self.alignment(desc[1][0])
        return 4

    def unpack(self, t: str) -> str:
        key = f"_s_{t}"
        self.env[key] = struct.Struct("<" + _FMT[t]).unpack_from
        return key

    def dtype(self, t: str) -> str:
        key = f"_d_{t}"
        self.env[key] = np.dtype(_NP.get(t, t))
        return key

    # -- fields -------------------------------------------------------------------------------
    def struct(self, typename: str, tree: dict | None, obj: str | None, ind: int) -> None:
        """Walk a message of ``typename``; store the fields in ``tree`` on ``obj``."""
        for fname, desc in self.store.get_msgdef(typename).fields:
            if not self.cdr and fname == "structure_needs_at_least_one_member":
                continue
            want = tree is not None and fname in tree
            target = f"{obj}.{fname}" if want else None
            sub = tree.get(fname) if tree is not None and want else None
            self.field(desc, target, sub, ind)

    def field(self, desc, target: str | None, sub: dict | None, ind: int) -> None:
        """Walk one field (rosbags field descriptor ``desc``: node type 1 base, 2 nested
        message, 3 array, 4 sequence); store it in ``target`` when wanted (``sub``: the
        wanted fields of a nested message)."""
        kind = desc[0]
        self.align(self.alignment(desc), ind)
        if kind == 1:
            t = desc[1][0]
            if t == "string":
                self.string(target, ind)
            else:
                if target:
                    self.read(t, target)
                self.off += _SIZE[t]
        elif kind == 2:
            if sub is not None and target:
                cls = self.message_class(desc[1], sub)
                var = self.name("o")
                self.emit(ind, f"{var} = {cls}()")
                self.struct(desc[1], sub, var, ind)
                self.emit(ind, f"{target} = {var}")
            else:
                self.struct(desc[1], None, None, ind)
        elif kind == 3:
            self.array(desc[1], target, ind)
        else:
            self.sequence(desc[1][0], target, ind)

    def array(self, spec, target: str | None, ind: int) -> None:
        """A fixed-length array (``spec``: element descriptor, length): no count."""
        elem, length = spec
        if elem[0] == 1 and elem[1][0] != "string":
            t = elem[1][0]
            if target:
                self.emit(ind, f"{target} = np.frombuffer(raw, {self.dtype(t)}, {length}, "
                               f"{self.at()})")
            self.off += length * _SIZE[t]
        elif elem[0] == 1:
            vals = self.name("v") if target else None
            if vals:
                self.emit(ind, f"{vals} = []")
            for i in range(length):
                if i:
                    self.align(4, ind)
                self.string(f"{vals}.append" if vals else None, ind, call=True)
            if target:
                self.emit(ind, f"{target} = {vals}")
        else:
            if target:
                raise _NotCovered("an array of messages is wanted")
            for i in range(length):
                if i:
                    self.align(self.alignment(elem), ind)
                self.struct(elem[1], None, None, ind)

    def sequence(self, elem, target: str | None, ind: int) -> None:
        """A sequence of ``elem``: a uint32 count, then the elements."""
        count = self.name("n")
        self.emit(ind, f"{count} = _u32(raw, {self.at()})[0]")
        self.off += 4
        if elem[0] == 1 and elem[1][0] != "string":
            t = elem[1][0]
            size = _SIZE[t]
            self.flush(ind)
            if self.cdr and size > 4:
                self.emit(ind, f"if {count}:")
                self.emit(ind + 1, f"pos = (pos + {size - 1}) & -{size}")
            if target:
                self.emit(ind, f"{target} = np.frombuffer(raw, {self.dtype(t)}, {count}, "
                               f"{self.at()})")
            self.emit(ind, f"pos += {count} * {size}" if size > 1 else f"pos += {count}")
            self.known = min(4, size) if self.cdr else 1
            return
        if target and elem[0] != 1:
            raise _NotCovered("a sequence of messages is wanted")
        self.flush(ind)
        self.emit(ind, f"if {count} > len(raw):")
        self.emit(ind + 1, "raise ValueError('sequence count beyond the message')")
        vals = self.name("v") if target else None
        if vals:
            self.emit(ind, f"{vals} = []")
        self.emit(ind, f"for _ in range({count}):")
        self.known = 1
        if elem[0] == 1:
            self.align(4, ind + 1)
            self.string(f"{vals}.append" if vals else None, ind + 1, call=True)
        else:
            self.align(self.alignment(elem), ind + 1)
            self.struct(elem[1], None, None, ind + 1)
        self.flush(ind + 1)
        self.known = 1
        if vals:
            self.emit(ind, f"{target} = {vals}")

    def string(self, target: str | None, ind: int, call: bool = False) -> None:
        ln = self.name("l")
        self.emit(ind, f"{ln} = _u32(raw, {self.at()})[0]")
        start = self.off + self.base + 4
        if self.cdr:
            # rosbags' check: length >= 1, inside the message, NUL-terminated
            self.emit(ind, f"if {ln} < 1 or raw[pos + {start} + {ln} - 1] != 0:")
            self.emit(ind + 1, "raise ValueError('bad string')")
            value = f"raw[pos + {start}:pos + {start} + {ln} - 1].decode()"
        else:
            self.emit(ind, f"if pos + {start} + {ln} > len(raw):")
            self.emit(ind + 1, "raise ValueError('bad string')")
            value = f"raw[pos + {start}:pos + {start} + {ln}].decode()"
        if target:
            self.emit(ind, f"{target}({value})" if call else f"{target} = {value}")
        else:  # not wanted, but checked as rosbags does (UTF-8)
            self.emit(ind, value)
        self.off += 4
        self.flush(ind)
        self.emit(ind, f"pos += {ln}")
        self.known = 1

    def message_class(self, typename: str, tree: dict) -> str:
        key = self.name("M")
        clsname = getattr(self.store.types.get(typename), "__name__", typename)
        self.env[key] = _message_class(typename, tuple(tree), clsname)
        return key


_CLASSES: dict[tuple[str, tuple[str, ...], str], type] = {}


def _message_class(typename: str, names: tuple[str, ...], clsname: str) -> type:
    """A slotted class with only ``names``; named and with ``__msgtype__`` as rosbags'
    class of the type (so messages naming the type read the same)."""
    key = (typename, names, clsname)
    cls = _CLASSES.get(key)
    if cls is None:
        def __repr__(self):
            inner = ", ".join(f"{n}={getattr(self, n, None)!r}" for n in names)
            return f"{typename}({inner}; selectively decoded)"

        cls = type(clsname, (),
                   {"__slots__": names, "__msgtype__": typename, "__repr__": __repr__})
        _CLASSES[key] = cls
    return cls


def _generate(store, typename: str, paths: Iterable[Path], cdr: bool) -> Callable[[bytes], Any]:
    tree = _tree(store, typename, set(paths))
    g = _Gen(store, cdr)
    top = g.message_class(typename, tree)
    body_start = len(g.lines)
    g.emit(1, "pos = 0")
    g.emit(1, f"o0 = {top}()")
    g.struct(typename, tree, "o0", 1)
    g.flush(1)
    if cdr:
        # rosbags: at most 3 bytes of padding after the last field, none missing
        g.emit(1, "if pos + 4 > len(raw) or pos + 7 < len(raw):")
    else:
        g.emit(1, "if pos != len(raw):")
    g.emit(2, "raise ValueError('size mismatch')")
    g.emit(1, "return o0")
    head = ["def decode(raw):"]
    if cdr:
        head.append("    if raw[0] != 0 or raw[1] != 1:")
        head.append("        raise ValueError('not little-endian CDR')")
    src = "\n".join(head + g.lines[body_start:]) + "\n"
    code = compile(src, f"<fretc selective {typename}>", "exec")
    exec(code, g.env)
    fn = g.env["decode"]
    fn.source = src
    return fn


def selective_decoder(store: Typestore, typename: str, message_encoding: str,
                      paths: Iterable[Path] | None, full: Callable[[bytes], Any]
                      ) -> Callable[[bytes], Any] | None:
    """A decoder of ``typename`` messages reading only ``paths`` (see the module docstring),
    or None when the fast path does not cover them (then use ``full``).

    Args:
        store: the rosbags Typestore holding ``typename`` (built from the log's schema).
        message_encoding: ``"cdr"`` or ``"ros1"``.
        paths: field paths (tuples of names and indexes); None means every field (None is
            returned: the full decoder is the one for that).
        full: the full decoder; used for any message the fast path cannot read, so that
            errors are rosbags' own.
    """
    if paths is None or message_encoding not in ("cdr", "ros1") or sys.byteorder != "little":
        return None
    try:
        fast = _generate(store, typename, paths, message_encoding == "cdr")
    except _NotCovered:
        stats["full_types"] += 1
        return None
    stats["fast_types"] += 1

    def decode(raw: bytes) -> Any:
        try:
            return fast(raw)
        except Exception:
            stats["fallback_messages"] += 1
            return full(raw)

    decode.fast = fast  # type: ignore[attr-defined]  # the fast path, for the tests
    return decode
