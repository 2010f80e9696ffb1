"""MCAP files (MCAP specification, any profile): the record layer and its CRCs, a damaged
file's intact parts, the indexed pass a chunk at a time as columns, and MCAP's message
encodings beside ROS's (``json``, ``protobuf``, ``cbor``).

Modules: :mod:`.source` :class:`~fretc.logs.mcap.source.McapSource`; :mod:`.records` the
framing; :mod:`.integrity` the summary, the data-section CRC and what a file cut short holds;
:mod:`.columns` the indexed pass as columns; :mod:`.encodings` the ``json``, ``protobuf``
and ``cbor`` channels and their schemas, :mod:`.json_values` JSON values as message objects.

May import: ``fretc.common``, :mod:`fretc.logs.base`, the log layer's shared modules
(:mod:`fretc.logs.decoding`, :mod:`fretc.logs.field_select`, :mod:`fretc.logs.reorder`,
:mod:`fretc.logs.recorded_gaps`) and :mod:`fretc.logs.ros` (the CDR of ROS 2 channels); not
:mod:`fretc.logs.flight` nor :mod:`fretc.logs.csv`.
"""
