"""Verdicts back into the data: a copy of each audited MCAP with a ``foxglove.Log`` channel of
verdict events (``fretc report --annotate DIR``), so a violation shows in Foxglove's Log panel
next to the robot's topics.

Design notes: ARCHITECTURE.md, `audit/annotate.py`."""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

from mcap.records import (Attachment, Channel, Chunk, DataEnd, Header, Message, Metadata,
                          Schema)
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

from fretc.common.outputs import open_output, output_folder
from fretc.common.units import format_offset
from fretc.logs.mcap.records import chunk_records

__all__ = ["VERDICT_TOPIC", "FOXGLOVE_LOG_SCHEMA", "VerdictEvent", "AnnotateResult",
           "verdict_events", "annotate_mcap", "LEVELS"]

VERDICT_TOPIC = "/fretc/verdicts"

#: foxglove.LogLevel values.
LEVELS = {"UNKNOWN": 0, "DEBUG": 1, "INFO": 2, "WARNING": 3, "ERROR": 4, "FATAL": 5}

#: JSON schema of foxglove.Log (fields timestamp, level, message, name, file, line).
FOXGLOVE_LOG_SCHEMA = {
    "title": "foxglove.Log",
    "description": "A log message",
    "$comment": "foxglove.Log as in foxglove/schemas schemas/jsonschema/Log.json",
    "type": "object",
    "properties": {
        "timestamp": {
            "type": "object", "title": "time",
            "properties": {"sec": {"type": "integer", "minimum": 0},
                           "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}},
            "description": "Timestamp of log message",
        },
        "level": {
            "title": "foxglove.LogLevel", "description": "Log level",
            "oneOf": [{"title": name, "const": value} for name, value in LEVELS.items()],
        },
        "message": {"type": "string", "description": "Log message"},
        "name": {"type": "string", "description": "Process or node name"},
        "file": {"type": "string", "description": "Filename"},
        "line": {"type": "integer", "minimum": 0, "description": "Line number in the file"},
    },
}


@dataclass(frozen=True)
class VerdictEvent:
    """One foxglove.Log message: ``time_ns`` on the log clock, ``level`` a key of
    :data:`LEVELS`, ``kind`` (trigger, violation, ltl3, verdict), the requirement id, its
    file and line."""

    time_ns: int
    level: str
    kind: str
    requirement: str
    message: str
    file: str = ""
    line: int = 0

    def to_json(self) -> dict:
        """The event as a ``foxglove.Log`` message (timestamp in s and ns, level, message, name,
        file, line)."""
        sec, nsec = divmod(max(0, int(self.time_ns)), 1_000_000_000)
        return {"timestamp": {"sec": sec, "nsec": nsec}, "level": LEVELS[self.level],
                "message": self.message, "name": f"fretc/{self.requirement}",
                "file": self.file, "line": int(self.line)}


@dataclass
class AnnotateResult:
    """What :func:`annotate_mcap` wrote: ``messages`` copied, ``events`` added, ``partial``
    (the original is damaged; ``damage`` says where reading stopped), the ``compression``
    used."""

    source: str
    output: str
    messages: int = 0
    events: int = 0
    partial: bool = False
    damage: str | None = None
    compression: str = ""
    channels: int = 0
    schemas: int = 0


_s = functools.partial(format_offset, missing="?")


def verdict_events(log: dict) -> list[VerdictEvent]:
    """The events of one log object of the audit JSON (``fretc-audit/1``), sorted by time
    (then by requirement order, then kind). A log whose audit failed (``error``) or that has
    no tick gives none."""
    start = log.get("start_time_ns")
    end = log.get("end_time_ns")
    out: list[tuple[int, int, int, VerdictEvent]] = []
    order = {"trigger": 0, "violation": 1, "ltl3": 2, "verdict": 3}
    for i, v in enumerate(log.get("verdicts") or []):
        rid = v.get("requirement", "?")
        src = v.get("source") or ""
        file, _, line = src.rpartition(":")
        if not line.isdigit():
            file, line = src, "0"
        text = v.get("text") or ""

        def add(ns, level, kind, message):
            if ns is None:
                return
            # add is called in this iteration only: the loop's variables are this verdict's
            ev = VerdictEvent(int(ns), level, kind, rid, message, file, int(line))  # noqa: B023
            out.append((int(ns), i, order[kind], ev))  # noqa: B023

        fv = v.get("first_violation")
        verdict = v.get("verdict")
        if verdict == "violated" and fv:
            trig = fv.get("trigger")
            if trig:
                add(trig["time_ns"], "WARNING", "trigger",
                    f"{rid} trigger at tick {trig['tick']} ({_s(trig['time_ns'], start)}): "
                    f"obligation {fv.get('obligation', '')} - {text}")
            add(fv["log_time_ns"], "ERROR", "violation",
                f"{rid} VIOLATED at tick {fv['tick']} ({_s(fv['log_time_ns'], start)}): "
                f"{fv.get('reason', '')} - {text}")
            # the later failed triggers (the audit lists the first ones)
            listed = v.get("violation_list") or []
            for k, item in enumerate(listed[1:], start=2):
                w = item["violation"]
                add(w["time_ns"], "ERROR", "violation",
                    f"{rid} violation {k} of {v.get('violations')}: trigger at tick "
                    f"{item['trigger']['tick']}, missed at tick {w['tick']} "
                    f"({_s(w['time_ns'], start)}) - {text}")
        l3 = v.get("ltl3") or {}
        if l3.get("status") in ("violated", "satisfied") and l3.get("time_ns") is not None:
            add(l3["time_ns"], "ERROR" if l3["status"] == "violated" else "INFO", "ltl3",
                f"{rid} LTL3 verdict {l3['status']} at tick {l3.get('tick')} "
                f"({_s(l3['time_ns'], start)}): earliest definitive verdict of ft_inf - {text}")
        level = {"satisfied": "INFO", "vacuous": "INFO", "violated": "ERROR"}.get(verdict,
                                                                                   "WARNING")
        detail = ""
        if verdict == "violated" and fv:
            detail = f", first violation at {_s(fv['log_time_ns'], start)}"
        elif verdict == "error":
            detail = f": {v.get('error')}"
        elif v.get("notes"):
            detail = f" ({'; '.join(v['notes'])})"
        partial = " (partial log)" if v.get("partial") else ""
        add(end, level, "verdict",
            f"{rid} finite-trace verdict: {verdict}{partial}{detail} - {text}")
    out.sort(key=lambda t: t[:3])
    return [t[3] for t in out]


def _compression_of(path: str) -> tuple[str | None, int]:
    """(compression of the first chunk: '' for none, None when the file has no chunk before
    its first message, i.e. unchunked; the first chunk's uncompressed size, the chunk size
    the copy is written with)."""
    default = 1024 * 1024
    with open(path, "rb") as fh:
        try:
            for rec in StreamReader(fh, emit_chunks=True).records:
                if isinstance(rec, Chunk):
                    return rec.compression, max(1024, int(rec.uncompressed_size))
                if isinstance(rec, Message):
                    return None, default
        except Exception:  # noqa: BLE001 - damaged before any chunk: mcap's default
            pass
    return "zstd", default


class _Copy:
    """The copy being written: the original's records re-registered in the writer, the
    verdict events merged in by log time."""

    def __init__(self, fout, events: list[VerdictEvent], res: AnnotateResult, comp: str | None,
                 chunk_size: int, library: str):
        self.fout, self.events, self.res = fout, events, res
        self.comp, self.chunk_size, self.library = comp, chunk_size, library
        self.writer: Writer | None = None
        self.schemas: dict[int, int] = {}
        self.channels: dict[int, int] = {}
        self.verdict_channel: int | None = None
        self.ev_i = 0

    def start(self, profile: str, lib: str) -> None:
        ctype = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                 "": CompressionType.NONE, None: CompressionType.NONE
                 }.get(self.comp, CompressionType.ZSTD)
        w = Writer(self.fout, chunk_size=self.chunk_size, compression=ctype,
                   use_chunking=self.comp is not None)
        library = self.library
        w.start(profile=profile, library=f"{library} (copy of {lib})" if lib else library)
        self.writer = w

    def emit_events(self, until_ns: int | None) -> None:
        """Write the events before ``until_ns`` (all when None)."""
        events, writer = self.events, self.writer
        assert writer is not None  # (start() made it)
        while self.ev_i < len(events) and (until_ns is None
                                           or events[self.ev_i].time_ns < until_ns):
            if self.verdict_channel is None:
                sid = writer.register_schema(
                    "foxglove.Log", "jsonschema",
                    json.dumps(FOXGLOVE_LOG_SCHEMA, sort_keys=True).encode())
                self.verdict_channel = writer.register_channel(
                    VERDICT_TOPIC, "json", sid, {"generator": "fretc report --annotate"})
            ev = events[self.ev_i]
            writer.add_message(self.verdict_channel, ev.time_ns,
                               json.dumps(ev.to_json(), sort_keys=True).encode(),
                               ev.time_ns, self.ev_i)
            self.ev_i += 1
            self.res.events += 1

    def handle(self, rec) -> None:
        """Copy one record of the original's data section (not a chunk)."""
        writer = self.writer
        assert writer is not None  # (start() made it)
        if isinstance(rec, Schema):
            if rec.id not in self.schemas:
                self.schemas[rec.id] = writer.register_schema(rec.name, rec.encoding, rec.data)
        elif isinstance(rec, Channel):
            if rec.id not in self.channels:
                sid = self.schemas.get(rec.schema_id, 0) if rec.schema_id else 0
                self.channels[rec.id] = writer.register_channel(
                    rec.topic, rec.message_encoding, sid, dict(rec.metadata))
        elif isinstance(rec, Message):
            self.emit_events(rec.log_time)
            writer.add_message(self.channels[rec.channel_id], rec.log_time, rec.data,
                               rec.publish_time, rec.sequence)
            self.res.messages += 1
        elif isinstance(rec, Metadata):
            writer.add_metadata(rec.name, dict(rec.metadata))
        elif isinstance(rec, Attachment):
            writer.add_attachment(rec.create_time, rec.log_time, rec.name, rec.media_type,
                                  rec.data)

    def copy(self, reader: StreamReader) -> None:
        """Copy the data section up to its end or the damage (then ``res.partial``)."""
        res = self.res
        records = iter(reader.records)
        while True:
            try:
                rec = next(records)
            except StopIteration:
                break
            except Exception as exc:  # noqa: BLE001 - mcap raises many kinds on damage
                # a damaged or truncated original: keep what was read before the damage
                res.partial = True
                res.damage = f"{type(exc).__name__}: {exc}"
                break
            if isinstance(rec, Header):
                self.start(rec.profile, rec.library)
            elif isinstance(rec, DataEnd):
                break  # the summary section repeats what was already copied
            elif self.writer is None:
                continue
            elif isinstance(rec, Chunk):
                try:
                    inner = chunk_records(rec)
                except Exception as exc:  # noqa: BLE001 - a corrupt chunk is skipped
                    res.partial = True
                    res.damage = f"chunk at {rec.message_start_time} ns skipped: {exc}"
                    continue
                for r in inner:
                    self.handle(r)
            else:
                self.handle(rec)

    def finish(self, log: dict) -> None:
        """The events after the last message, the ``fretc.verdicts`` metadata, the end."""
        if self.writer is None:
            self.start("", "")
        self.emit_events(None)
        assert self.writer is not None  # (start() made it)
        self.writer.add_metadata("fretc.verdicts", {
            str(v.get("requirement")): str(v.get("verdict")) + (" (partial log)"
                                                               if v.get("partial") else "")
            for v in log.get("verdicts") or []})
        self.writer.finish()


def annotate_mcap(source: str, output: str, log: dict, *, library: str = "fretc report"
                  ) -> AnnotateResult:
    """Copy the MCAP ``source`` to ``output`` with the verdict channel of ``log`` (a log
    object of the audit JSON for this file).

    Returns:
        :class:`AnnotateResult`.

    Raises:
        OSError: ``source`` cannot be read or ``output`` written.
        ValueError: ``source`` is not an MCAP file (bad magic).
    """
    with open(source, "rb") as fh:
        if fh.read(8) != b"\x89MCAP0\r\n":
            raise ValueError(f"{source}: not an MCAP file")
    comp, chunk_size = _compression_of(source)
    events = verdict_events(log)
    res = AnnotateResult(source=source, output=output,
                         compression=comp if comp is not None else "unchunked")
    output_folder(Path(output).parent)
    # a temporary file renamed over the output (never written through a link planted there)
    with open(source, "rb") as fin, open_output(output, "wb") as fout:
        copy = _Copy(fout, events, res, comp, chunk_size, library)
        copy.copy(StreamReader(fin, emit_chunks=True, validate_crcs=True))
        copy.finish(log)
    extra = 1 if copy.verdict_channel is not None else 0
    res.channels = len(copy.channels) + extra
    res.schemas = len(copy.schemas) + extra
    return res
