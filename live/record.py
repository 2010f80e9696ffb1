"""The recording of a watch (``fretc watch --record``): an MCAP of the watched messages, with
their schemas and encodings as advertised, plus the ``/fretc/verdicts`` ``foxglove.Log``
channel of verdict events (:mod:`fretc.audit.annotate`) and the run's gaps (a lost connection,
a publisher that left: :mod:`fretc.logs.recorded_gaps`), written at the end. ``fretc audit`` of
the recording gives the watch's verdicts."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING
from mcap.writer import CompressionType, Writer

from fretc.common.outputs import create_output
from fretc.audit.annotate import FOXGLOVE_LOG_SCHEMA, VERDICT_TOPIC, verdict_events
from fretc.logs.recorded_gaps import GAPS_METADATA, gaps_json

if TYPE_CHECKING:
    from collections.abc import Sequence

    from fretc.audit.verdict import LogAudit
    from fretc.logs.base import Gap

__all__ = ["Recorder"]


class Recorder:
    """MCAP of the watched messages (schemas and encodings as advertised) plus the
    ``/fretc/verdicts`` foxglove.Log channel, written at the end."""

    def __init__(self, path: str, source) -> None:
        self.path = path
        self.source = source
        self._f = create_output(path)  # (a link planted at path is replaced, not followed)
        self.writer = Writer(self._f, compression=CompressionType.ZSTD)
        self.writer.start(profile="", library="fretc watch")
        self.channels: dict[str, int] = {}
        self.seq: dict[str, int] = {}

    def message(self, topic: str, log_time: int, payload: bytes) -> None:
        """Write one watched message (its channel and schema on first use)."""
        cid = self.channels.get(topic)
        if cid is None:
            ch = self.source.advertised[topic]
            sid = self.writer.register_schema(ch.schema_name, ch.schema_encoding,
                                              ch.schema.encode("utf-8"))
            cid = self.writer.register_channel(topic, ch.encoding, sid)
            self.channels[topic] = cid
            self.seq[topic] = 0
        self.writer.add_message(cid, log_time=log_time, data=payload, publish_time=log_time,
                                sequence=self.seq[topic])
        self.seq[topic] += 1

    def finish(self, la: LogAudit, gaps: Sequence[Gap] = ()) -> int:
        """Write the verdict events of ``la`` and the run's ``gaps``
        (:func:`fretc.live.absence.recorded_gaps`: the metadata :data:`GAPS_METADATA`, which
        :class:`fretc.logs.McapSource` reads back as gaps of the log) and close the file;
        the number of events."""
        events = verdict_events(la.to_json())
        sid = self.writer.register_schema("foxglove.Log", "jsonschema",
                                          json.dumps(FOXGLOVE_LOG_SCHEMA).encode("utf-8"))
        cid = self.writer.register_channel(VERDICT_TOPIC, "json", sid)
        for i, e in enumerate(sorted(events, key=lambda e: e.time_ns)):
            self.writer.add_message(cid, log_time=int(e.time_ns), publish_time=int(e.time_ns),
                                    data=json.dumps(e.to_json()).encode("utf-8"), sequence=i)
        self.writer.add_metadata("fretc.verdicts",
                                 {v.requirement: v.verdict for v in la.verdicts})
        if gaps:
            self.writer.add_metadata(GAPS_METADATA, {"gaps": gaps_json(gaps)})
        self.close()
        return len(events)

    def close(self) -> None:
        """Close the file (its summary written), without verdict events."""
        self.writer.finish()
        self._f.close()


