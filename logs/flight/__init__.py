"""Flight logs: PX4 ULog (with pyulog, PX4's own reader) and ArduPilot DataFlash (with
pymavlink's ``DFReader``), their damage found before they are read.

Modules: :mod:`.ulog` :class:`~fretc.logs.flight.ulog.UlogSource`, :mod:`.ulog_framing` its
framing checked (cuts, damage, the intact runs around it), :mod:`.ulog_fast` a sound log's
data read at once (numpy); :mod:`.dataflash` :class:`~fretc.logs.flight.dataflash.DataflashSource`.

May import: ``fretc.common``, :mod:`fretc.logs.base` and the log layer's shared modules
(:mod:`fretc.logs.field_select`, :mod:`fretc.logs.reorder`); not the other formats'
subpackages.
"""
