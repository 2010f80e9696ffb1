"""A synthetic tracked-obstacles recording for the per-entity benchmark
(``bench_audit.py --entities``).

``write_tracks(path, minutes)`` writes a ROS 2 MCAP with ``/tracks``
(``tracking_msgs/msg/TrackArray``: ``Track[] tracks``, each ``uint32 id``, ``float64
distance``) at 10 Hz: obstacles appear, approach and recede, and disappear, about three
tracked at a time, each for about ten minutes, ids counting up. Deterministic (a fixed
seed). ``tracks_reference`` recomputes, per id, the first message at which a tracked
obstacle is at most ``bound`` metres away (numpy, from the generated values, not the log).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

EPOCH_NS = 1_700_000_000 * 1_000_000_000
PERIOD_NS = 100_000_000


def _store():
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg("uint32 id\nfloat64 distance", "tracking_msgs/msg/Track"))
    store.register(get_types_from_msg("tracking_msgs/Track[] tracks",
                                      "tracking_msgs/msg/TrackArray"))
    return store


def _tracks(minutes: float, seed: int = 11) -> list[dict[int, float]]:
    """Per message, id -> distance (m) of the obstacles tracked then."""
    rng = np.random.default_rng(seed)
    n = int(minutes * 600)
    life = 6000  # messages: ten minutes at 10 Hz
    rows: list[dict[int, float]] = [{} for _ in range(n)]
    start, ident = 0, 1
    while start < n:
        for _ in range(3):
            s = start + int(rng.integers(0, life // 2))
            e = min(n, s + int(rng.integers(life // 2, life)))
            closest = float(rng.uniform(0.3, 3.0))
            k = np.arange(s, e)
            d = closest + 4.0 * np.abs(np.sin(np.pi * (k - s) / max(1, e - s) - np.pi / 2))
            for i, x in zip(k.tolist(), np.round(d, 3).tolist()):
                rows[i][ident] = x
            ident += 1
        start += life
    return rows


def _write_rows(path: str | Path, rows: list[dict[int, float]]) -> int:
    """Write ``rows`` (per message, id -> distance in m) as ``/tracks`` at 10 Hz to ``path``
    (ROS 2 MCAP); returns the number of messages. Raises ``OSError``."""
    store = _store()
    Track, Arr = store.types["tracking_msgs/msg/Track"], store.types["tracking_msgs/msg/TrackArray"]
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="fretc-bench")
        text = store.generate_msgdef("tracking_msgs/msg/TrackArray", ros_version=2)[0]
        sid = w.register_schema("tracking_msgs/msg/TrackArray", "ros2msg", text.encode())
        ch = w.register_channel("/tracks", "cdr", sid)
        for k, r in enumerate(rows):
            t = EPOCH_NS + k * PERIOD_NS
            msg = Arr(tracks=[Track(id=i, distance=d) for i, d in sorted(r.items())])
            w.add_message(ch, log_time=t, publish_time=t, data=bytes(
                store.serialize_cdr(msg, "tracking_msgs/msg/TrackArray")), sequence=k)
        w.finish()
    return len(rows)


def write_tracks(path: str | Path, minutes: float) -> int:
    """Write ``minutes`` of ``/tracks`` to ``path``; returns the number of messages.

    Raises ``OSError`` if the file cannot be written.
    """
    return _write_rows(path, _tracks(minutes))


def _first_close(rows: list[dict[int, float]], bound: float) -> dict[int, int | None]:
    """Id -> log time (ns) of the first of ``rows`` (messages at 10 Hz) where it is at most
    ``bound`` metres away, None if never."""
    out: dict[int, int | None] = {}
    for k, r in enumerate(rows):
        for i, d in r.items():
            out.setdefault(i, None)
            if d <= bound and out[i] is None:
                out[i] = EPOCH_NS + k * PERIOD_NS
    return out


def tracks_reference(minutes: float, bound: float) -> dict[int, int | None]:
    """Id -> log time (ns) of the first message where that obstacle is tracked at most
    ``bound`` metres away, None if never: the first violation of ``in present mode ...
    always satisfy dist > bound`` per entity."""
    return _first_close(_tracks(minutes), bound)


def many_tracks(entities: int, alive: int = 5) -> list[dict[int, float]]:
    """Per message, id -> distance (m): ``entities`` obstacles, each tracked for ``alive``
    messages, a new one every message (so ``alive`` at a time); one in 100 comes within
    0.5 m once (its 3rd message), the others stay beyond 1.5 m. Deterministic."""
    rows: list[dict[int, float]] = [{} for _ in range(entities + alive - 1)]
    for i in range(entities):
        for age in range(alive):
            close = i % 100 == 7 and age == 2
            rows[i + age][i + 1] = 0.4 if close else 1.5 + ((i * 7 + age * 3) % 40) / 10
    return rows


def write_many_tracks(path: str | Path, entities: int, alive: int = 5) -> int:
    """Write :func:`many_tracks` as ``/tracks`` at 10 Hz to ``path`` (ROS 2 MCAP); returns
    the number of messages. Raises ``OSError`` if the file cannot be written."""
    return _write_rows(path, many_tracks(entities, alive))


def many_reference(entities: int, alive: int = 5, bound: float = 1.0) -> dict[int, int | None]:
    """Id -> log time (ns) of the first message where that obstacle of :func:`many_tracks`
    is at most ``bound`` metres away, None if never."""
    return _first_close(many_tracks(entities, alive), bound)
