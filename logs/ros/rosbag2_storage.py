"""rosbag2's sqlite3 storage files (``.db3``) read as rosbag2 itself reads them:

* :func:`stored_definitions`: the definitions a storage file keeps in its
  ``message_definitions`` table (schema version 4, Iron and later), by type name. rosbag2
  stores a service event topic's definition under the *service's* type (its ``.srv`` text,
  ``example_interfaces/srv/AddTwoInts``: rosbag2_cpp ``SequentialWriter::create_topic`` looks
  the definition up for the service type), not the event type the topic names, so a reader
  that looks the topic's type up finds none; :func:`fretc.logs.ros.bags.connection_typestore`
  builds the event's definition from it (:func:`fretc.logs.decoding.service_event_text`).
* :func:`storage_folder`: a storage file given alone (a ``.db3``, or a folder holding one
  without ``metadata.yaml``), which ``ros2 bag info``/``play`` open with the storage
  plugin alone: a temporary rosbag2 folder for the rosbags reader, its ``metadata.yaml``
  made from the file's own tables (topics, their messages' counts and times), the file
  linked into it.
"""

from __future__ import annotations

import os
import shutil
import sqlite3
import tempfile
from contextlib import closing
from pathlib import Path

from fretc.common.problems import LogError

__all__ = ["stored_definitions", "storage_folder", "lone_storage"]


def _connect(path: Path) -> sqlite3.Connection:
    """A connection to the storage file ``path`` that writes nothing: read-only and
    immutable (SQLite's URI parameters ``mode=ro&immutable=1``, sqlite.org/uri.html: no
    lock, no ``-shm``/``-wal`` file beside a WAL-mode database, so the evidence folder is
    left as it was and a bag on read-only media opens). A recorded bag is read, never one
    being written. The path percent-encoded as a ``file:`` URI (``?`` and ``#`` in a
    name). The caller closes it."""
    return sqlite3.connect(Path(path).resolve().as_uri() + "?mode=ro&immutable=1", uri=True)


def stored_definitions(folder: Path) -> dict[str, tuple[str, str]]:
    """Type name -> (encoding, text) of the definitions the ``.db3`` files of a rosbag2
    ``folder`` keep (empty for other storage, older schemas, unreadable files)."""
    out: dict[str, tuple[str, str]] = {}
    for db in sorted(folder.glob("*.db3")):
        try:
            with closing(_connect(db)) as c:
                rows = c.execute("SELECT topic_type, encoding, encoded_message_definition "
                                 "FROM message_definitions ORDER BY id").fetchall()
        except sqlite3.Error:
            continue
        for name, encoding, text in rows:
            out.setdefault(str(name), (str(encoding), str(text)))
    return out


def lone_storage(path: Path) -> Path | None:
    """The storage file of ``path`` when it is one given alone: a ``.db3`` file, or a folder
    without ``metadata.yaml`` holding exactly one ``.db3``; else None."""
    if path.is_file() and path.suffix.lower() == ".db3":
        return path
    if path.is_dir() and not (path / "metadata.yaml").exists():
        found = sorted(path.glob("*.db3"))
        return found[0] if len(found) == 1 else None
    return None


def _metadata(db: Path, name: str) -> str:
    """A rosbag2 ``metadata.yaml`` (version 5: rosbags reads it) of the storage file ``db``
    linked as ``name``, from its ``topics`` and ``messages`` tables.

    Raises:
        LogError: the file is not a rosbag2 sqlite3 storage file."""
    try:
        with closing(_connect(db)) as c:
            topics = c.execute("SELECT id, name, type, serialization_format, "
                               "offered_qos_profiles FROM topics ORDER BY id").fetchall()
            counts = dict(c.execute("SELECT topic_id, count(*) FROM messages "
                                    "GROUP BY topic_id").fetchall())
            n, first, last = c.execute("SELECT count(*), min(timestamp), max(timestamp) "
                                       "FROM messages").fetchone()
    except sqlite3.Error as exc:
        raise LogError(db, f"not a rosbag2 sqlite3 storage file ({exc})") from None
    first = first if first is not None else 0
    duration = (last - first + 1) if last is not None else 0
    lines = ["rosbag2_bagfile_information:", "  version: 5", "  storage_identifier: sqlite3",
             f"  duration:\n    nanoseconds: {duration}",
             f"  starting_time:\n    nanoseconds_since_epoch: {first}",
             f"  message_count: {n}", "  topics_with_message_count:"]
    for tid, tname, ttype, fmt, qos in topics:
        qos_text = (qos or "").replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        lines += ["    - topic_metadata:", f"        name: {_quoted(tname)}",
                  f"        type: {_quoted(ttype)}",
                  f"        serialization_format: {_quoted(fmt)}",
                  f'        offered_qos_profiles: "{qos_text}"',
                  f"      message_count: {counts.get(tid, 0)}"]
    if not topics:
        lines[-1] += " []"
    lines += ['  compression_format: ""', '  compression_mode: ""',
              f"  relative_file_paths:\n    - {_quoted(name)}",
              f"  files:\n    - path: {_quoted(name)}",
              f"      starting_time:\n        nanoseconds_since_epoch: {first}",
              f"      duration:\n        nanoseconds: {duration}",
              f"      message_count: {n}"]
    return "\n".join(lines) + "\n"


def _quoted(text: object) -> str:
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def storage_folder(db: Path) -> Path:
    """A temporary rosbag2 folder holding the storage file ``db`` (linked, or copied where
    links cannot be made) and a ``metadata.yaml`` made from it (module docstring); the
    caller removes it (:func:`shutil.rmtree`).

    Raises:
        LogError: ``db`` is not a rosbag2 sqlite3 storage file."""
    folder = Path(tempfile.mkdtemp(prefix="fretc-rosbag2-"))
    name = db.name
    try:
        try:
            os.symlink(db.resolve(), folder / name)
        except OSError:
            shutil.copyfile(db, folder / name)
        (folder / "metadata.yaml").write_text(_metadata(db, name), encoding="utf-8")
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return folder
