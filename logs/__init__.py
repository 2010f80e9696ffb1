"""Log sources: recorded robot runs read as a stream of decoded messages in log-time order.

``open_log(path)`` (:mod:`fretc.logs.factory`) picks a reader by what ``path`` is:

Design notes: ARCHITECTURE.md, `logs/__init__.py`."""

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
