"""Message schemas of a log: the field paths of each topic's type, with their types.

Used to check signal bindings against a log before it is audited (a string in
arithmetic, a boolean used as a number and the reverse, a field the message type does not
declare - each an error naming the variable, the topic and the field) and by
``fretc inspect`` (the field paths a binding can name).

Design notes: ARCHITECTURE.md, `logs/schema.py`."""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TYPE_CHECKING

from fretc.common.errors import InputError

from fretc.logs.csv.source import CSV_TOPIC
from fretc.logs.decoding import UnsupportedSchema, build_typestore
from fretc.logs.mcap.encodings import SELF_DESCRIBING, definition

if TYPE_CHECKING:
    from fretc.logs.base import LogSource

__all__ = ["FieldType", "TopicSchema", "FieldPathError", "LogSchemas", "log_schemas",
           "record_schemas", "field_paths", "closest"]

_NUMBER = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
           "float32", "float64", "byte", "char", "octet"}
_STRING = {"string", "wstring"}


@dataclass(frozen=True)
class FieldType:
    """The type of a field (module docstring): ``kind``, the ROS ``name`` (``float64``,
    ``pkg/msg/Type``), for arrays the ``item`` type and the fixed ``length`` (None: a
    sequence of any length)."""

    kind: str
    name: str
    item: FieldType | None = None
    length: int | None = None

    def text(self) -> str:
        """The type as bindings and ``fretc inspect`` print it (``float64``, ``float32[360]``)."""
        if self.kind == "array" and self.item is not None:  # (an array has its item type)
            return f"{self.item.text()}[{'' if self.length is None else self.length}]"
        return self.name


class FieldPathError(InputError, ValueError):
    """A field path that the schema does not declare; ``valid`` lists the fields that exist
    at the point where it failed and ``suggestion`` is the closest one (or None)."""

    def __init__(self, message: str, valid: list[str], suggestion: str | None) -> None:
        super().__init__(message)
        self.valid = valid
        self.suggestion = suggestion


def closest(name: str, candidates: list[str]) -> str | None:
    """The candidate closest to ``name`` (difflib ratio >= 0.6), or None."""
    got = difflib.get_close_matches(name, candidates, n=1, cutoff=0.6)
    return got[0] if got else None


class TopicSchema:
    """One topic's message type with its rosbags typestore (``fields`` of a type name)."""

    def __init__(self, topic: str, typename: str, store: Any) -> None:
        self.topic = topic
        self.typename = typename
        self.store = store

    def fields(self, typename: str | None = None) -> list[tuple[str, FieldType]]:
        """(name, type) of the fields of ``typename`` (default: the topic's type)."""
        _consts, fields = self.store.fielddefs[typename or self.typename]
        return [(n, self._type(spec)) for n, spec in fields]

    def _type(self, spec) -> FieldType:
        node, sub = spec
        node = int(node)
        if node == 1:  # BASE
            base = sub[0]
            kind = ("bool" if base == "bool" else "number" if base in _NUMBER
                    else "string" if base in _STRING else "unknown")
            return FieldType(kind, base)
        if node == 2:  # NAME
            return FieldType("message", sub)
        item, length = sub
        return FieldType("array", "array", self._type(item), length if node == 3 else None)

    def constants(self, typename: str | None = None) -> dict[str, Any]:
        """The named constants of a message definition (``uint8 POWER_SUPPLY_STATUS_CHARGING
        = 1``): name -> value (int, float, bool or str), in declaration order."""
        consts, _fields = self.store.fielddefs[typename or self.typename]
        return {c[0]: c[2] for c in consts}

    def resolve(self, path: tuple) -> FieldType:
        """The type at ``path`` (field names, integer indexes, slices and filters, as in
        :class:`fretc.signals.bindings.expression.Field`). From the first slice or filter on,
        the path applies to each item of the array and the type is an array of the result
        (Foxglove's message path semantics).

        Raises:
            FieldPathError: a name the type does not declare (with the valid ones and the
                closest), an index into something that is not an array, a field of an array
                or of a number, a filter on what is not an array of messages.
        """
        cur = FieldType("message", self.typename)
        walked = self.topic
        many = False
        for p in path:
            kind = type(p).__name__
            if kind in ("Slice", "Filter"):
                if cur.kind == "array" and cur.item is not None:  # its items (a filter right
                    cur, many = cur.item, True  # after a slice: the same); an array has them
                elif kind == "Slice" or not many:
                    how = "sliced" if kind == "Slice" else "filtered"
                    raise FieldPathError(f"{walked} is a {cur.text()}, not an array: it "
                                         f"cannot be {how}", [], None)
                walked += p.text()
                if kind == "Filter":
                    self._check_filter(cur, p, walked)
                continue
            if isinstance(p, int):
                cur = self._index(cur, p, walked)
                walked += f"[{p}]"
                continue
            cur = self._member(cur, p, walked)
            walked += f".{p}"
        return FieldType("array", "array", cur, None) if many else cur

    def _index(self, cur: FieldType, p: int, walked: str) -> FieldType:
        if cur.kind != "array":
            raise FieldPathError(f"{walked} is a {cur.text()}, not an array: it cannot "
                                 f"be indexed", [], None)
        if cur.length is not None and not -cur.length <= p < cur.length:
            raise FieldPathError(f"{walked}[{p}]: index out of range (the array has "
                                 f"{cur.length} items)", [], None)
        assert cur.item is not None  # (an array has its item type)
        return cur.item

    def _member(self, cur: FieldType, p: str, walked: str) -> FieldType:
        if cur.kind != "message":
            what = "an array" if cur.kind == "array" else f"a {cur.text()}"
            raise FieldPathError(f"{walked} is {what}: it has no field {p!r}", [], None)
        fields = dict(self.fields(cur.name))
        if p not in fields:
            valid = list(fields)
            hint = closest(p, valid)
            raise FieldPathError(
                f"{walked}: a {cur.name} has no field {p!r} (its fields: "
                f"{', '.join(valid)})" + (f"; did you mean {hint!r}?" if hint else ""),
                valid, hint)
        return fields[p]

    def check_message_filter(self, flt: Any) -> None:
        """A filter written right after the topic (``/track{id==3}``, FoxQL): its field must
        be a bool, number or string of the topic's message, of the kind of the literal.

        Raises:
            FieldPathError: as :meth:`resolve`.
        """
        self._check_filter(FieldType("message", self.typename), flt, self.topic + flt.text())

    def _check_filter(self, item: FieldType, flt: Any, walked: str) -> None:
        """A filter's field must be a bool, number or string of the item message, and a
        literal it is compared with of the same kind."""
        if item.kind != "message":
            raise FieldPathError(f"{walked}: only arrays of messages can be filtered "
                                 f"(the items are {item.text()})", [], None)
        t = item
        for name in flt.path:
            t = self._member(t, name, walked)
        if t.kind not in ("bool", "number", "string"):
            raise FieldPathError(f"{walked}: the filter's field is a {t.text()}, not a "
                                 "boolean, a number or a string", [], None)
        value = getattr(flt.value, "value", None)
        if value is not None and (isinstance(value, str) != (t.kind == "string")):
            raise FieldPathError(f"{walked}: the filter compares a {t.text()} field with "
                                 f"{'a string' if isinstance(value, str) else 'a number'}",
                                 [], None)


class CsvSchema(TopicSchema):
    """The ``/csv`` pseudo-topic of a CSV trace: one field per column (bool or number)."""

    def __init__(self, topic: str, columns: dict[str, str]) -> None:
        super().__init__(topic, "csv", None)
        self.columns = columns

    def fields(self, typename: str | None = None) -> list[tuple[str, FieldType]]:
        """(column, type) of every CSV column: ``bool`` or a ``float64`` number."""
        return [(c, FieldType("bool" if t == "bool" else "number",
                              "bool" if t == "bool" else "float64"))
                for c, t in self.columns.items()]

    def resolve(self, path: tuple) -> FieldType:
        """The type of the column ``path`` names. Raises
        :class:`fretc.common.problems.FieldPathError` for an unknown column (the closest one named)."""
        cols = [c for c, _ in self.fields()]
        if not path or not isinstance(path[0], str) or path[0] not in self.columns:
            name = path[0] if path else ""
            hint = closest(str(name), cols)
            raise FieldPathError(
                f"{self.topic}: the CSV has no column {name!r} (columns: {', '.join(cols)})"
                + (f"; did you mean {hint!r}?" if hint else ""), cols, hint)
        t = dict(self.fields())[path[0]]
        if len(path) > 1:
            raise FieldPathError(f"{self.topic}.{path[0]} is a CSV column ({t.name}): it has "
                                 f"no fields", [], None)
        return t


def field_paths(schema: TopicSchema, limit_depth: int = 8) -> Iterator[tuple[str, FieldType]]:
    """Every field path of the topic's type (``pose.pose.position.x``), depth first, with
    its type; arrays are listed with ``[]`` and the fields of their items below."""
    def walk(prefix: str, typename: str, depth: int):
        if depth > limit_depth:
            return
        for name, t in schema.fields(typename):
            path = f"{prefix}.{name}" if prefix else name
            yield path, t
            inner = t.item if t.kind == "array" else t
            if inner is not None and inner.kind == "message":
                yield from walk(path + ("[]" if t.kind == "array" else ""), inner.name,
                                depth + 1)
    if isinstance(schema, CsvSchema):
        yield from schema.fields()
        return
    yield from walk("", schema.typename, 0)


# --------------------------------------------------------------------------- reading
class LogSchemas(Mapping):
    """Topic -> :class:`TopicSchema` (or None) of one log, each topic's built on its first
    access: building one parses its definition and compiles rosbags' (de)serializers (tens
    of ms a type), and an audit reads the few topics its bindings name, where a flight log
    defines sixty types or more. Keys are sorted; the values are what an eager build gives.

    Args:
        builders: topic -> a function giving its schema (None: no usable schema).
    """

    def __init__(self, builders: dict[str, Callable[[], TopicSchema | None]]) -> None:
        self._builders = dict(sorted(builders.items()))
        self._built: dict[str, TopicSchema | None] = {}

    def __getitem__(self, topic: str) -> TopicSchema | None:
        if topic not in self._built:
            self._built[topic] = self._builders[topic]()
        return self._built[topic]

    def __iter__(self) -> Iterator[str]:
        return iter(self._builders)

    def __len__(self) -> int:
        return len(self._builders)


def log_schemas(source: LogSource) -> Mapping[str, TopicSchema | None]:
    """Topic -> :class:`TopicSchema` of an open log (:func:`fretc.logs.open_log`), built on first
    access (:class:`LogSchemas`); None for a topic whose schema is missing or cannot be
    parsed (the reader reports it as ``unknown_schema``). Reads only the schema and channel
    records (the summary of an MCAP, the connection headers of a bag), never the
    messages."""
    kind = source.kind
    if kind == "csv":
        return {CSV_TOPIC: CsvSchema(CSV_TOPIC, dict(getattr(source, "types", {}) or
                                                     {c: "float" for c in source.columns}))}  # type: ignore[attr-defined]  # a CsvSource
    if kind == "mcap":
        return _mcap_schemas(source)
    if kind in ("ulog", "dataflash"):
        return _defined_schemas(source)
    return _bag_schemas(source)


def _defined_schemas(source) -> LogSchemas:
    """Schemas of a source that gives each topic's ROS 2 definition (``definitions()``)."""
    def builder(topic: str, typ: str, text: str) -> Callable[[], TopicSchema | None]:
        def build() -> TopicSchema | None:
            built = _build("ros2msg", typ, text)
            return TopicSchema(topic, built[1], built[0]) if built else None
        return build
    return LogSchemas({topic: builder(topic, typ, text)
                       for topic, (typ, text) in source.definitions().items()})


def _build(encoding: str, name: str, text: str) -> tuple[Any, str] | None:
    try:
        return build_typestore(encoding, name, text)
    except UnsupportedSchema:
        return None


def _mcap_schemas(source) -> LogSchemas:
    # the source's own Schema and Channel records (its summary, or its bounded linear scan
    # of the data section): never the mcap library's stream reader, which decompresses a
    # chunk whatever size it declares. A topic's schema is that of its first channel (by
    # id) whose schema can be built.
    schemas, channels = source._channels()
    by_topic: dict[str, list] = {}
    for ch in sorted(channels.values(), key=lambda c: c.id):
        by_topic.setdefault(ch.topic, []).append(ch)

    def one(ch) -> tuple[Any, str] | None:
        sc = schemas.get(ch.schema_id)
        if ch.message_encoding in SELF_DESCRIBING:
            found = definition(ch.message_encoding, sc.encoding if sc else "",
                               sc.name if sc else "", bytes(sc.data) if sc else None)
            return _build("ros2msg", *found) if found else None
        if sc is not None and sc.name:
            return _build(sc.encoding, sc.name, sc.data.decode("utf-8", errors="replace"))
        return None

    def builder(topic: str, chans: list) -> Callable[[], TopicSchema | None]:
        def build() -> TopicSchema | None:
            for ch in chans:
                built = one(ch)
                if built:
                    return TopicSchema(topic, built[1], built[0])
            return None
        return build
    return LogSchemas({t: builder(t, chans) for t, chans in by_topic.items()})


def record_schemas(records: Mapping[str, tuple[str, str, str, bytes]]) -> LogSchemas:
    """Topic -> :class:`TopicSchema` (or None) built from topic -> (message encoding, schema
    encoding, schema name, schema data), as an MCAP channel and its schema record give them
    (a live source's advertisements: the watch checks the bindings' types with them)."""
    def builder(topic: str, rec: tuple[str, str, str, bytes]
                ) -> Callable[[], TopicSchema | None]:
        def build() -> TopicSchema | None:
            encoding, schema_encoding, name, data = rec
            if encoding in SELF_DESCRIBING:
                found = definition(encoding, schema_encoding, name, data or None)
                built = _build("ros2msg", *found) if found else None
            else:
                built = (_build(schema_encoding, name, data.decode("utf-8", errors="replace"))
                         if name else None)
            return TopicSchema(topic, built[1], built[0]) if built else None
        return build
    return LogSchemas({t: builder(t, rec) for t, rec in records.items()})


def _bag_schemas(source) -> dict[str, TopicSchema | None]:
    from rosbags.rosbag1 import Reader as Ros1Reader  # lazy: bags only (start-up)
    from rosbags.rosbag2 import Reader as Ros2Reader
    from fretc.logs.ros.bags import connection_typestore

    out: dict[str, TopicSchema | None] = {}
    linear = getattr(source, "_linear_bag", None)
    if linear is not None:  # a ROS 1 bag read record by record: its index is unusable
        for topic, typ, text in linear.conns.values():
            if out.get(topic) is None:
                built = _build("ros1msg", typ, text)
                out[topic] = TopicSchema(topic, built[1], built[0]) if built else None
        return dict(sorted(out.items()))
    reader_class = Ros1Reader if source.kind == "bag" else Ros2Reader
    with reader_class(getattr(source, "_read_path", Path(source.path))) as reader:
        for c in reader.connections:
            if out.get(c.topic) is not None:
                continue
            try:
                built = connection_typestore(source.kind, c, getattr(source, "_fallback", None),
                                             getattr(source, "_stored", None))
            except UnsupportedSchema:
                built = None
            out[c.topic] = TopicSchema(c.topic, built[1], built[0]) if built else None
    return dict(sorted(out.items()))
