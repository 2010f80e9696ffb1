"""The factory: :func:`open_log` chooses the source class by what the path is (as the
``mcap`` library's ``make_reader`` chooses a reader class)."""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from typing import TYPE_CHECKING

from fretc.common.units import NS_PER_S

from fretc.common.problems import LogError
from fretc.logs.base import LogSource
from fretc.logs.csv.source import CsvSource

if TYPE_CHECKING:
    from fretc.logs.csv.read import RowSink
    from rosbags.typesys import Stores
    from rosbags.typesys.store import Typestore

__all__ = ["open_log", "unseekable"]


def unseekable(path: str | os.PathLike) -> str | None:
    """Why the log at ``path`` cannot be read, when it is neither a regular file nor a folder
    (a FIFO, ``/dev/stdin``, a shell's ``<(...)`` as ``/dev/fd/N``, a character device), else
    None. fretc reads a log more than once and out of order (MCAP's summary and index at
    its end, its chunks by offset; a CSV read again for ``--write-csv``; a shielded
    recording's span read twice), which a stream cannot give: it is refused, naming the
    path, before any byte is read from it (issue 91: such a log ended in an internal
    error). Links are followed (``os.stat``)."""
    import stat

    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None  # (missing: the caller's own error)
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    kind = ("a FIFO (a named pipe, or a shell's <(...))" if stat.S_ISFIFO(mode) else
            "a character device" if stat.S_ISCHR(mode) else
            "a socket" if stat.S_ISSOCK(mode) else "not a regular file")
    return (f"{kind}, not a file: fretc reads a log more than once and out of order (an "
            "MCAP's index, a CSV's second read), which a stream cannot give; save it to a "
            "file first (e.g. `cat > run.mcap`) and audit that")


def open_log(path: str | os.PathLike, *, fallback_typestore: Typestore | Stores | None = None,
             check_data_crc: bool = True, csv_period_ns: int = NS_PER_S,
             msg_path: Sequence[str] = (), csv_keep: Iterable[str] | None = None,
             csv_sink: RowSink | None = None, csv_streamed: Iterable[str] = (),
             csv_keep_times: bool = True, csv_extent: int | None = None) -> LogSource:
    """Open a recorded run for reading.

    Args:
        path: ``*.mcap`` file, ROS 1 ``*.bag`` file, rosbag2 folder (with ``metadata.yaml``),
            a rosbag2 sqlite3 storage file alone (``*.db3``, or a folder holding one),
            ``*.csv`` trace, PX4 ULog ``*.ulg`` or ArduPilot DataFlash ``*.bin`` flight log.
        fallback_typestore: types for rosbag connections that carry no definition (e.g. old
            rosbag2 sqlite3 bags): a rosbags Typestore or a ``rosbags.typesys.Stores`` member.
            Never used when the log embeds its definitions. Default: ROS 2 Humble's standard
            types plus the types defined under ``msg_path`` (:mod:`fretc.logs.ros.msg_path`).
        msg_path: folders of ``.msg``/``.idl`` files (``--msg-path``).
        check_data_crc: MCAP only: check the DataEnd data-section CRC (one extra read of the
            data section after a full indexed pass).
        csv_period_ns: CSV only: time step between rows when there is no ``time`` column.
        csv_keep: CSV only: the columns whose values are kept (None: every one; the
            others are checked but not kept, :class:`~fretc.logs.csv.source.CsvSource`).
        csv_sink, csv_streamed, csv_keep_times: CSV only: the columns ``csv_streamed``
            handed to ``csv_sink`` a chunk of rows at a time as the file is read, and
            whether the rows' times are kept (:class:`~fretc.logs.csv.source.CsvSource`).
        csv_extent: CSV only: the bytes of the file read, from its start (None: its size
            when opened); an audit that reads a trace again passes the first read's
            ``extent``, so a file still growing is judged over the same rows by every pass.

    Returns:
        A :class:`LogSource` (McapSource, BagSource, CsvSource, UlogSource or
        DataflashSource).

    Raises:
        LogError: missing path, unknown kind, or a file that cannot be opened as that kind.
        CsvError: a bad CSV trace (names file:line).
        InputError: a ``msg_path`` folder that is missing or holds a bad definition.
    """
    # each reader is imported only for its kind of log (start-up of an audit)
    p = Path(path)
    if not p.exists():
        raise LogError(path, "no such file or folder")
    refused = unseekable(p)
    if refused is not None:
        raise LogError(path, refused)
    suffix = p.suffix.lower()
    if p.is_dir() or suffix in (".bag", ".db3"):
        from rosbags.typesys import Stores, get_typestore
        from fretc.logs.ros.bags import BagSource
        from fretc.logs.ros.msg_path import fallback_for
        from fretc.logs.ros.rosbag2_storage import lone_storage

        if isinstance(fallback_typestore, Stores):
            fallback_typestore = get_typestore(fallback_typestore)
        if fallback_typestore is None:
            fallback_typestore = fallback_for(msg_path)
        if p.is_dir() and not (p / "metadata.yaml").exists() and lone_storage(p) is None:
            raise LogError(path, "a folder but not a rosbag2 bag (no metadata.yaml, nor one "
                                 "sqlite3 storage file .db3)")
        return BagSource(p, fallback_typestore=fallback_typestore)
    if suffix == ".mcap":
        from fretc.logs.mcap.source import McapSource

        return McapSource(p, check_data_crc=check_data_crc)
    if suffix == ".csv":
        return CsvSource(p, period_ns=csv_period_ns, keep=csv_keep, sink=csv_sink,
                         streamed=csv_streamed, keep_times=csv_keep_times,
                         extent=csv_extent)
    if suffix == ".ulg":
        from fretc.logs.flight.ulog import UlogSource

        return UlogSource(p)
    if suffix == ".bin":
        from fretc.logs.flight.dataflash import DataflashSource

        return DataflashSource(p)
    raise LogError(path, "unknown log kind (expected .mcap, .bag, .db3, .csv, .ulg, .bin or "
                         "a rosbag2 folder)")
