"""Log sources: recorded robot runs read as a stream of decoded messages in log-time order.

``open_log(path)`` (:mod:`fretc.logs.factory`) picks a reader by what ``path`` is:

* ``*.mcap`` — any MCAP profile (:mod:`fretc.logs.mcap.source`).  Messages on channels
  with ``cdr`` (ROS 2) or ``ros1`` message encoding are deserialized with rosbags types built
  from the schema *embedded in the file* (``ros2msg``, ``ros2idl``, ``ros1msg`` schema
  encodings; MCAP spec, "Well-known encodings"; :mod:`fretc.logs.decoding`).  Chunk
  CRCs and the data-section CRC are checked.  A file with a valid footer and summary is read
  through its chunk indexes; a file without one (a crashed recording) is read record by
  record from the start, as far as it goes (:mod:`fretc.logs.mcap.integrity`).
* ``*.bag`` — a ROS 1 bag (rosbags.rosbag1), types from the connection headers; without its
  index it is read record by record (:mod:`fretc.logs.ros.ros1_linear`).
* a folder with ``metadata.yaml`` — a rosbag2 bag (rosbags.rosbag2, sqlite3 or mcap storage),
  types from the definitions stored in the bag (or a fallback typestore, see ``open_log``)
  (:mod:`fretc.logs.ros.bags`).
* ``*.csv`` — a trace of FRET variables: a header row of variable names, one row per tick
  (:mod:`fretc.logs.csv.source`).
* ``*.ulg`` — a PX4 ULog (pyulog; :mod:`fretc.logs.flight.ulog`); ``*.bin`` — an ArduPilot
  DataFlash log (pymavlink; :mod:`fretc.logs.flight.dataflash`).

Each format family is a subpackage (:mod:`.mcap`, :mod:`.ros`, :mod:`.flight`, :mod:`.csv`)
that imports only the shared modules at this package's top (:mod:`.base`, :mod:`.decoding`,
:mod:`.field_select`, :mod:`.reorder`, :mod:`.recorded_gaps`, :mod:`.schema`), and MCAP
also :mod:`.ros` (a ROS 2 channel's CDR).

Every source gives :class:`Message` tuples in non-decreasing log time, streaming: memory does
not grow with the length of the log (:mod:`fretc.logs.base`; the passes without an
index restore log-time order with :mod:`fretc.logs.reorder`).  Damage is recorded as
:class:`~fretc.common.problems.DataProblem` in ``source.problems`` and reading goes on; see
:class:`LogSource`.

Times are integer nanoseconds since the epoch of the recording clock (MCAP ``log_time``,
rosbag ``timestamp``).
"""

from __future__ import annotations

import importlib

from fretc.logs.base import LogSource, Message, header_stamp
from fretc.logs.csv.source import CSV_TOPIC, CSV_TYPE, CsvRow, CsvSource
from fretc.logs.decoding import DECODE_ERRORS, UnsupportedSchema, build_typestore, schema_decoder
from fretc.logs.factory import open_log
from fretc.logs.reorder import REORDER_WINDOW_NS

#: the readers of one kind of log each, imported when first named (an audit of a flight log
#: does not load the bag readers, nor an audit of an MCAP file pyulog)
_READERS = {"McapSource": ".mcap.source", "BagSource": ".ros.bags",
            "UlogSource": ".flight.ulog", "DataflashSource": ".flight.dataflash"}


def __getattr__(name: str):
    module = _READERS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module, __name__), name)


#: The former name of :class:`UnsupportedSchema` (``live/watch.py`` imports it).
_Unsupported = UnsupportedSchema

__all__ = [
    "Message",
    "LogSource",
    "header_stamp",
    "schema_decoder",
    "build_typestore",
    "UnsupportedSchema",
    "DECODE_ERRORS",
    "McapSource",
    "UlogSource",
    "DataflashSource",
    "BagSource",
    "CsvSource",
    "CsvRow",
    "open_log",
    "CSV_TOPIC",
    "CSV_TYPE",
    "REORDER_WINDOW_NS",
]
