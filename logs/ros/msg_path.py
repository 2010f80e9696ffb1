"""Message types that are not in the log: a team's own ``.msg`` / ``.idl`` files
(``--msg-path DIR``), for bags that store no definitions (rosbag2 sqlite3 bags of the
Humble era) and connections whose definition is missing.

Design notes: ARCHITECTURE.md, `logs/ros/msg_path.py`."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from fretc.common.errors import InputError

__all__ = ["MSG_PATH_HINT", "msg_path_typestore", "definitions_in", "fallback_for", "types_of"]

#: How a user gives fretc the types a log does not carry (the option's own words).
MSG_PATH_HINT = ("--msg-path DIR (a folder of .msg/.idl/.srv/.action files laid out as "
                 "PKG/msg/TYPE.msg, PKG/srv/NAME.srv, PKG/action/NAME.action, or a ROS 2 "
                 "install/ or share/ tree)")


def definitions_in(folder: str | Path) -> dict[str, Path]:
    """Type name (``pkg/msg/Type``) -> definition file of every ``PKG/msg/TYPE.msg`` or
    ``.idl`` under ``folder`` (the first found, in sorted path order, wins).

    Raises:
        InputError: ``folder`` is not a folder.
    """
    root = Path(folder)
    if not root.is_dir():
        raise InputError(str(folder), "--msg-path: not a folder")
    out: dict[str, Path] = {}
    for p in sorted(root.rglob("*")):
        kind = _KINDS.get(p.suffix)
        if kind is not None and p.parent.name == kind and p.is_file():
            out.setdefault(f"{p.parent.parent.name}/{kind}/{p.stem}", p)
    return out


#: Definition file suffix -> the folder it lies in (``PKG/<folder>/TYPE<suffix>``).
_KINDS = {".msg": "msg", ".idl": "msg", ".srv": "srv", ".action": "action"}
#: service_msgs/msg/ServiceEventInfo (ROS 2 Iron and later), for the services' events.
_EVENT_INFO = ("uint8 REQUEST_SENT = 0\nuint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\n"
               "uint8 RESPONSE_RECEIVED = 3\nuint8 event_type\nbuiltin_interfaces/Time stamp\n"
               "char[16] client_gid\nint64 sequence_number\n")


def _parts(text: str, count: int) -> list[str]:
    """The ``---``-separated parts of a ``.srv`` (2) or ``.action`` (3) text."""
    parts: list[list[str]] = [[]]
    for line in text.splitlines():
        if line.strip() == "---":
            parts.append([])
        else:
            parts[-1].append(line)
    if len(parts) != count:
        raise ValueError(f"{len(parts)} parts separated by --- (expected {count})")
    return ["\n".join(p) + "\n" for p in parts]


def _service(name: str, request: str, response: str) -> dict:
    """The types of service ``pkg/srv/NAME`` (or an action's ``pkg/action/NAME``): its
    request, response and introspection event."""
    types = get_types_from_msg(request, f"{name}_Request")
    types.update(get_types_from_msg(response, f"{name}_Response"))
    types.update(get_types_from_msg(
        f"service_msgs/ServiceEventInfo info\n{name}_Request[<=1] request\n"
        f"{name}_Response[<=1] response\n", f"{name}_Event"))
    return types


def types_of(name: str, path: Path, text: str) -> dict:
    """The rosbags types a definition file defines (module docstring): ``name`` is
    ``pkg/msg/T``, ``pkg/srv/T`` or ``pkg/action/T``.

    Raises:
        Exception: rosbags' parsers' own, on text they cannot parse."""
    if path.suffix == ".idl":
        return get_types_from_idl(text)
    if path.suffix == ".msg":
        return get_types_from_msg(text, name)
    if path.suffix == ".srv":
        return _service(name, *_parts(text, 2))
    goal, result, feedback = _parts(text, 3)
    types = get_types_from_msg(goal, f"{name}_Goal")
    types.update(get_types_from_msg(result, f"{name}_Result"))
    types.update(get_types_from_msg(feedback, f"{name}_Feedback"))
    types.update(get_types_from_msg(f"unique_identifier_msgs/UUID goal_id\n{name}_Feedback "
                                    "feedback\n", f"{name}_FeedbackMessage"))
    types.update(_service(f"{name}_SendGoal", f"unique_identifier_msgs/UUID goal_id\n"
                          f"{name}_Goal goal\n", "bool accepted\nbuiltin_interfaces/Time stamp\n"))
    types.update(_service(f"{name}_GetResult", "unique_identifier_msgs/UUID goal_id\n",
                          f"int8 status\n{name}_Result result\n"))
    return types


@functools.lru_cache(maxsize=8)
def msg_path_typestore(folders: tuple[str, ...]) -> Typestore:
    """ROS 2 Humble's standard types plus every type defined under ``folders``.

    Raises:
        InputError: a folder that does not exist, a definition rosbags cannot parse, or one
            that contradicts a type already known (naming the file).
    """
    store = get_typestore(Stores.ROS2_HUMBLE)
    if "service_msgs/msg/ServiceEventInfo" not in store.fielddefs:
        store.register(get_types_from_msg(_EVENT_INFO, "service_msgs/msg/ServiceEventInfo"))
    for folder in folders:
        for name, path in definitions_in(folder).items():
            text = path.read_text(encoding="utf-8", errors="replace")
            try:
                types = types_of(name, path, text)
            except Exception as exc:  # rosbags' parsers raise plain exceptions on bad text
                raise InputError(str(path), f"the definition of {name} cannot be parsed: "
                                             f"{exc}") from None
            try:
                store.register(types)
            except Exception as exc:  # rosbags refuses a type defined twice differently
                raise InputError(str(path), f"{name}: {exc}") from None
    return store


def fallback_for(folders: Sequence[str]) -> Typestore:
    """:func:`msg_path_typestore` of ``folders`` in the order given."""
    return msg_path_typestore(tuple(str(f) for f in folders))
