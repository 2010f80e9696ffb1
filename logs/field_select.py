"""The fields the signal bindings read, picked from a decoded self-describing message
(``json``, ``protobuf``: :mod:`fretc.logs.mcap.encodings`) instead of converting all of it.

Design notes: ARCHITECTURE.md, `logs/field_select.py`."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from types import SimpleNamespace
from typing import Any

__all__ = ["field_tree", "json_picker", "pruned_schema", "protobuf_picker"]

#: field name -> sub-tree (the fields read of a nested message) or None (the value whole)
Tree = dict[str, Any]


def field_tree(paths: Iterable[tuple[Any, ...]] | None) -> Tree | None:
    """The tree of the fields read along ``paths`` (module docstring); None when the whole
    message is wanted (``paths`` None, or a path naming no field)."""
    from fretc.logs.ros.selective import HEADER_STAMP

    if paths is None:
        return None
    tree: Tree = {}
    for path in paths:
        if path == HEADER_STAMP:
            path = ("header", "stamp")
        names: list[str] = []
        for part in path:
            if not isinstance(part, str):
                break
            names.append(part)
        if not names:
            return None
        node: Tree | None = tree
        for k, name in enumerate(names):
            assert node is not None
            if k == len(names) - 1:
                node[name] = None
            elif name in node and node[name] is None:
                break  # the value is read whole already
            else:
                node = node.setdefault(name, {})
    if "ranges" in tree:
        tree.setdefault("range_min", None)
        tree.setdefault("range_max", None)
    return tree


def pruned_schema(spec: Any, tree: Tree | None) -> Any:
    """A JSON Schema node with only the ``properties`` ``tree`` reads (recursively); its own
    ``type`` and ``items`` kept (a value of another shape than the tree expects is checked
    as the full schema checks it)."""
    if tree is None or not isinstance(spec, dict):
        return spec
    props = spec.get("properties")
    out = dict(spec)
    if isinstance(props, dict):  # (in the schema's order: the check's order of errors)
        out["properties"] = {name: pruned_schema(sub_spec, tree[name])
                             for name, sub_spec in props.items() if name in tree}
    return out


def json_picker(tree: Tree, convert: Callable[[Any], Any]) -> Callable[[Any], Any]:
    """A function ``decoded JSON value -> message object`` holding the fields of ``tree``
    (each read value converted whole by ``convert``, :func:`fretc.logs.mcap.encodings.as_message`);
    a value that is no JSON object is converted whole (the extractor reports it as the full
    conversion would make it report)."""
    subs = [(name, None if sub is None else json_picker(sub, convert))
            for name, sub in tree.items()]

    def pick(value: Any) -> Any:
        if type(value) is not dict:
            return convert(value)
        out = SimpleNamespace()
        d = out.__dict__
        for name, sub in subs:
            if name in value:
                d[name] = convert(value[name]) if sub is None else sub(value[name])
        return out
    return pick


def protobuf_picker(descriptor: Any, tree: Tree,
                    convert: Callable[[Any, int, Any], Any],
                    plan: Callable[[Any], list[tuple[str, int, Any]]],
                    lies: Callable[[Any, frozenset[int] | None], None]
                    ) -> Callable[[Any], SimpleNamespace]:
    """A function ``parsed protobuf message -> message object`` holding the fields of
    ``tree`` (those the message type declares; a field it lacks is left out, as the full
    conversion has no such attribute). ``convert`` converts one field's value whole by its
    plan (:func:`fretc.logs.mcap.encodings.pb_value`), ``plan`` gives a type's plan, ``lies`` is
    the wire-type check restricted to the given field numbers. Raises ``ValueError`` where
    ``lies`` does."""
    by_name = {name: (how, dtype) for name, how, dtype in plan(descriptor)}
    numbers = frozenset(f.number for f in descriptor.fields if f.name in tree)
    steps: list[tuple[str, int, Any, Any]] = []
    for name, sub in tree.items():
        if name not in by_name:
            continue
        how, dtype = by_name[name]
        field = descriptor.fields_by_name[name]
        if sub is not None and how == 1:  # a nested message: its fields read
            steps.append((name, -1, None, protobuf_picker(field.message_type, sub, convert,
                                                          plan, lies)))
        else:
            steps.append((name, how, dtype, None))

    # (a field kept as it is, most of a message's, read without a call to convert it)
    order = [(name, how == 0 and sub is None, how, dtype, sub)
             for name, how, dtype, sub in steps]

    def pick(msg: Any) -> SimpleNamespace:
        lies(msg, numbers)
        out = SimpleNamespace()
        d = out.__dict__
        for name, plain, how, dtype, sub in order:
            value = getattr(msg, name)
            if plain:
                d[name] = value
            else:
                d[name] = sub(value) if sub is not None else convert(value, how, dtype)
        return out
    return pick
