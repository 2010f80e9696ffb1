"""Cyclone DDS's side of ROS 2 topics for ``fretc watch dds://`` and ``fretc replay --serve
dds://``: IDL struct types built at run time from rosbags' message definitions, the domain,
and the raw CDR samples read and written.

Design notes: ARCHITECTURE.md, `live/dds/idl_types.py`."""

from __future__ import annotations

import threading
from typing import Any, TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["idl_struct", "open_participant", "take_raw", "write_raw", "reader_qos",
           "writer_qos", "LOOPBACK_XML"]

#: A Cyclone DDS configuration that keeps a domain on the loopback interface, multicast
#: off, peers found by unicast on 127.0.0.1 (tests, rehearsals on one machine).
LOOPBACK_XML = """<CycloneDDS><Domain id="any"><General><Interfaces>
<NetworkInterface address="127.0.0.1"/></Interfaces><AllowMulticast>false</AllowMulticast>
</General><Discovery><ParticipantIndex>auto</ParticipantIndex>
<MaxAutoParticipantIndex>30</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/>
</Peers></Discovery></Domain></CycloneDDS>"""

_BASE = {"bool": "bool", "byte": "byte", "octet": "byte", "char": "uint8", "int8": "int8",
         "uint8": "uint8", "int16": "int16", "uint16": "uint16", "int32": "int32",
         "uint32": "uint32", "int64": "int64", "uint64": "uint64", "float32": "float32",
         "float64": "float64"}
_lock = threading.Lock()
_structs: dict[tuple[int, str], type] = {}
_domains: dict[int, object] = {}


def _member_type(store, node):
    from cyclonedds.idl import types as T

    kind, args = node
    kind = int(kind)
    if kind == 1:  # BASE: (name, string bound)
        name, bound = args
        if name in ("string", "wstring"):
            return T.bounded_str[bound] if bound else str  # type: ignore[misc]  # (subscripted at run time)
        t = _BASE[name]
        return bool if t == "bool" else getattr(T, t)
    if kind == 2:  # NAME: a nested message
        return idl_struct(store, args)
    inner, n = args
    sub = _member_type(store, inner)
    if kind == 3:  # ARRAY
        return T.array[sub, n]  # type: ignore[misc]  # (cyclonedds' types are subscripted at run time)
    return T.sequence[sub, n] if n else T.sequence[sub]  # type: ignore[misc]


def idl_struct(store: Typestore, typename: str) -> type:
    """The ``cyclonedds.idl.IdlStruct`` of ROS type ``typename`` (``pkg/msg/Type``) named
    ``pkg::msg::dds_::Type_``, built from ``store``'s definition (module docstring); one
    class per store and type.

    Raises:
        KeyError: ``store`` does not know the type or one it nests.
    """
    from cyclonedds.idl import make_idl_struct

    from fretc.live.ros2_names import dds_type

    key = (id(store), typename)
    with _lock:
        got = _structs.get(key)
    if got is not None:
        return got
    _consts, fields = store.fielddefs[typename]
    members = {}
    for name, node in fields:
        members[name + "_"] = _member_type(store, node)
    dds = dds_type(typename)
    cls = make_idl_struct(dds.rsplit("::", 1)[1], dds, members)
    with _lock:
        return _structs.setdefault(key, cls)


def open_participant(domain: int, config_file: str | None = None) -> Any:  # a DomainParticipant
    """A ``DomainParticipant`` on ``domain``: with ``config_file`` (Cyclone DDS XML, e.g.
    interfaces, peers, DDS Security / SROS2 settings) the domain is configured from it, else
    from ``CYCLONEDDS_URI`` or Cyclone DDS's defaults. One configuration per domain and
    process (Cyclone DDS's rule); a second one is ignored.

    Raises:
        OSError: the file cannot be read; cyclonedds.core.DDSException: the configuration is
        refused.
    """
    from cyclonedds.domain import Domain, DomainParticipant

    if config_file is not None:
        with _lock:
            if domain not in _domains:
                with open(config_file, encoding="utf-8") as f:
                    _domains[domain] = Domain(domain, f.read())
    return DomainParticipant(domain)


#: Samples a watch's DDS reader keeps before it takes them (KeepLast): a burst the reading
#: thread has not taken beyond this many overwrites the oldest ones, and DDS counts no such
#: loss (docs/guide/limits.md). Large, so that the watch's own bounded queue, which counts
#: and reports what it drops, is where a flood is cut.
READER_DEPTH = 20_000


def _policy(qos: Any, policy: Any) -> str | None:
    """The text of ``qos``'s ``policy`` (``"Policy.Reliability.BestEffort"``), None when the
    QoS (a ``cyclonedds.qos.Qos`` read from a publication) does not give it. Qos objects are
    indexed by policy type; they have no attribute per policy."""
    if qos is None:
        return None
    try:
        return str(qos[policy])
    except (KeyError, TypeError, IndexError):
        return None


def transient_local(offered: Any = None, topic: str = "") -> bool:
    """Whether :func:`reader_qos` asks ``topic``'s publisher offering ``offered`` for its
    stored samples (transient-local durability: latched topics, ``/tf_static``)."""
    from cyclonedds.qos import Policy

    dur = _policy(offered, Policy.Durability)
    return topic == "/tf_static" or (dur is not None and "Volatile" not in dur)


def reader_qos(offered: Any = None, topic: str = "") -> Any:  # cyclonedds Qos
    """The QoS a ROS 2 subscription to a publisher offering ``offered`` (a
    ``cyclonedds.qos.Qos``, or None) would use so as to match it: reliable when offered
    reliable, else best effort; transient-local when offered (and always for ``/tf_static``,
    REP 105's latched transforms), else volatile; keep the last :data:`READER_DEPTH`
    samples; member names ignored in matching types (module docstring)."""
    from cyclonedds.qos import Policy, Qos

    rel = _policy(offered, Policy.Reliability)
    reliable = rel is None or "BestEffort" not in rel
    transient = transient_local(offered, topic)
    return Qos(Policy.Reliability.Reliable(max_blocking_time=100_000_000) if reliable
               else Policy.Reliability.BestEffort,
               Policy.Durability.TransientLocal if transient else Policy.Durability.Volatile,
               Policy.History.KeepLast(READER_DEPTH),
               Policy.TypeConsistency.AllowTypeCoercion(ignore_member_names=True))


def writer_qos(topic: str = "") -> Any:  # a cyclonedds Qos
    """The replay's writer QoS: reliable, keep all (a slow reader slows the replay down
    rather than losing messages), transient-local for ``/tf_static``."""
    from cyclonedds.qos import Policy, Qos

    return Qos(Policy.Reliability.Reliable(max_blocking_time=5_000_000_000),
               Policy.History.KeepAll,
               Policy.Durability.TransientLocal if topic == "/tf_static"
               else Policy.Durability.Volatile)


def take_raw(reader: Any, n: int = 256) -> list[tuple[bytes, Any]]:  # a DataReader
    """Up to ``n`` samples of ``reader`` as (CDR bytes with header, SampleInfo); samples
    without data (an instance disposed, its writers gone) are skipped."""
    from cyclonedds._clayer import ddspy_take
    from cyclonedds.core import InstanceState, SampleState, ViewState

    got = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, n)
    if isinstance(got, int):
        return []
    return [(bytes(d), info) for d, info in got if info.valid_data]


def write_raw(writer: Any, data: bytes, source_ns: int) -> None:  # a DataWriter
    """Write the CDR bytes ``data`` (with header) with ``source_ns`` as the sample's source
    timestamp. Raises RuntimeError when Cyclone DDS refuses it."""
    from cyclonedds._clayer import ddspy_write_ts

    data = bytes(data)
    data = data.ljust((len(data) + 3) & ~3, b"\0")
    ret = ddspy_write_ts(writer._ref, data, int(source_ns))
    if ret < 0:
        raise RuntimeError(f"Cyclone DDS refused a sample (return code {ret})")
