"""Message types that are not in the log: a team's own ``.msg`` / ``.idl`` files
(``--msg-path DIR``), for bags that store no definitions (rosbag2 sqlite3 bags of the
Humble era) and connections whose definition is missing.

A folder is searched for message definitions laid out as ROS lays them out:
``PKG/msg/TYPE.msg`` or ``PKG/msg/TYPE.idl`` at any depth, which covers a package source tree,
a workspace's ``src/``, and a ROS 2 ``install/`` or ``share/`` tree
(``install/PKG/share/PKG/msg/TYPE.msg``). The types found are added to ROS 2 Humble's
standard messages (rosbags' type store), which serve the standard packages (``std_msgs``,
``geometry_msgs``, ``sensor_msgs``, ...) of bags that store no definitions; a folder that
defines a standard type differently is an input error naming the file.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from pathlib import Path

from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from fretc.common.errors import InputError

__all__ = ["MSG_PATH_HINT", "msg_path_typestore", "definitions_in", "fallback_for"]

#: How a user gives fretc the types a log does not carry (the option's own words).
MSG_PATH_HINT = ("--msg-path DIR (a folder of .msg/.idl files laid out as PKG/msg/TYPE.msg, "
                 "or a ROS 2 install/ or share/ tree)")


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
        if p.suffix in (".msg", ".idl") and p.parent.name == "msg" and p.is_file():
            out.setdefault(f"{p.parent.parent.name}/msg/{p.stem}", p)
    return out


@functools.lru_cache(maxsize=8)
def msg_path_typestore(folders: tuple[str, ...]) -> Typestore:
    """ROS 2 Humble's standard types plus every type defined under ``folders``.

    Raises:
        InputError: a folder that does not exist, a definition rosbags cannot parse, or one
            that contradicts a type already known (naming the file).
    """
    store = get_typestore(Stores.ROS2_HUMBLE)
    for folder in folders:
        for name, path in definitions_in(folder).items():
            text = path.read_text(encoding="utf-8", errors="replace")
            try:
                types = (get_types_from_idl(text) if path.suffix == ".idl"
                         else get_types_from_msg(text, name))
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
