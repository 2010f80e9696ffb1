"""ROS 2's naming rules on its middlewares, shared by the DDS and Zenoh transports of
``fretc watch`` and ``fretc replay --serve``: the watch's URLs, topic and type names on the
wire, rmw_zenoh's key expressions, liveliness tokens and attachments, and the ``ros2msg``
advertisement of a ROS type the watch decodes with :func:`fretc.logs.schema_decoder`.

Design notes: ARCHITECTURE.md, `live/ros2_names.py`."""

from __future__ import annotations

import functools
import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING
from urllib.parse import parse_qs, urlsplit

from rosbags.typesys.msg import normalize_msgtype

from fretc.live.protocol import Advertised

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["Ros2Url", "parse_url", "dds_topic", "ros_topic_of_dds", "dds_type", "ros_type",
           "zenoh_key", "zenoh_topic_key", "parse_zenoh_key", "LivelinessToken",
           "liveliness_token", "parse_liveliness", "attachment", "attachment_time",
           "standard_store", "advertisement", "DEFAULT_ZENOH_PORT", "LIVELINESS_PREFIX",
           "bridge_key", "bridge_liveliness", "parse_bridge_liveliness", "CLOCK_TOPIC",
           "normal_type", "cdr_clock_ns"]

#: The topic of the ROS clock (simulated time, ``use_sim_time``): the DDS and Zenoh watches read
#: it whether or not a requirement does; once it is published, messages take its time as their
#: log time.
CLOCK_TOPIC = "/clock"

#: rmw_zenoh's router and peers listen on TCP port 7447 by default.
DEFAULT_ZENOH_PORT = 7447
#: rmw_zenoh's admin space of graph liveliness tokens.
LIVELINESS_PREFIX = "@ros2_lv"
_ATTACH = struct.Struct("<qq")


@dataclass(frozen=True)
class Ros2Url:
    """A watch or serve address on a ROS 2 middleware.

    Attributes:
        transport: ``"dds"`` or ``"zenoh"``.
        domain: the ROS domain id (``ROS_DOMAIN_ID``; 0..232 for DDS, REP 2000's range).
        host, port: the Zenoh endpoint (``tcp/host:port``); empty / 0 for DDS.
        layout: Zenoh's key expressions: ``"rmw"`` (rmw_zenoh) or ``"bridge"``
            (zenoh-bridge-ros2dds); namespace: the bridge's namespace (``/``: none).
    """

    transport: str
    domain: int
    host: str = ""
    port: int = 0
    layout: str = "rmw"
    namespace: str = "/"

    @property
    def endpoint(self) -> str:
        """Zenoh's locator of the endpoint, ``tcp/host:port``."""
        return f"tcp/{self.host}:{self.port}"


def parse_url(url: str) -> Ros2Url:
    """``dds://DOMAIN`` (``dds://`` alone: domain 0) or ``zenoh://HOST:PORT[?domain=D]``,
    ``zenoh://HOST:PORT?layout=bridge[&namespace=/NS]`` (zenoh-bridge-ros2dds) ->
    :class:`Ros2Url`.

    Raises:
        ValueError: another scheme, a domain outside 0..232, a missing host, another layout,
            a namespace not starting with ``/``.
    """
    parts = urlsplit(url)
    if parts.scheme == "dds":
        text = (parts.netloc or parts.path.strip("/") or "0")
        if not text.isdigit() or not 0 <= int(text) <= 232:
            raise ValueError(f"{url!r}: the DDS domain is an integer 0..232 (dds://DOMAIN)")
        return Ros2Url("dds", int(text))
    if parts.scheme == "zenoh":
        if not parts.hostname:
            raise ValueError(f"{url!r}: expected zenoh://HOST:PORT")
        query = parse_qs(parts.query)
        q = query.get("domain", ["0"])[0]
        if not q.isdigit():
            raise ValueError(f"{url!r}: domain must be an integer")
        layout = query.get("layout", ["rmw"])[0]
        ns = query.get("namespace", ["/"])[0]
        if layout not in ("rmw", "bridge") or not ns.startswith("/"):
            raise ValueError(f"{url!r}: layout is rmw (rmw_zenoh) or bridge "
                             "(zenoh-bridge-ros2dds); a namespace starts with /")
        return Ros2Url("zenoh", int(q), parts.hostname, parts.port or DEFAULT_ZENOH_PORT,
                       layout, ns.rstrip("/") or "/")
    raise ValueError(f"{url!r}: expected dds://DOMAIN or zenoh://HOST:PORT")


def dds_topic(topic: str) -> str:
    """ROS topic ``/a/b`` -> DDS topic ``rt/a/b``."""
    return "rt/" + topic.lstrip("/")


def ros_topic_of_dds(name: str) -> str | None:
    """DDS topic ``rt/a/b`` -> ``/a/b``; None for a DDS topic that is no ROS topic (services
    ``rq/``/``rr/``, plain DDS)."""
    return "/" + name[3:] if name.startswith("rt/") else None


def dds_type(ros: str) -> str:
    """``pkg/msg/Type`` (or ``pkg/Type``) -> ``pkg::msg::dds_::Type_``; a service's types
    (``pkg/srv/Name_Event``, filed by rosbags as ``pkg/srv/msg/Name_Event``) ->
    ``pkg::srv::dds_::Name_Event_``, as rosidl names them on DDS."""
    parts = normalize_msgtype(ros).split("/")
    if len(parts) == 4 and parts[2] == "msg":  # pkg/srv/msg/Name, pkg/action/msg/Name
        return f"{parts[0]}::{parts[1]}::dds_::{parts[3]}_"
    pkg, kind, name = parts
    return f"{pkg}::{kind}::dds_::{name}_"


def ros_type(dds: str) -> str:
    """``pkg::msg::dds_::Type_`` -> ``pkg/msg/Type`` (another name is returned as it is, with
    ``::`` as ``/``)."""
    parts = dds.split("::")
    if len(parts) == 4 and parts[2] == "dds_" and parts[3].endswith("_"):
        return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"
    return dds.replace("::", "/")


def zenoh_topic_key(domain: int, topic: str) -> str:
    """The key expression of every message of ``topic`` whatever its type:
    ``D/a/b/*/*``."""
    return f"{domain}/{topic.strip('/')}/*/*"


def zenoh_key(domain: int, topic: str, ros: str, type_hash: str) -> str:
    """The key expression of rmw_zenoh for a message of ``topic`` of type ``ros``."""
    return f"{domain}/{topic.strip('/')}/{dds_type(ros)}/{type_hash}"


def parse_zenoh_key(key: str) -> tuple[int, str, str, str] | None:
    """rmw_zenoh's data key expression -> (domain, topic, ROS type, type hash); None when it
    is not one."""
    parts = key.split("/")
    if len(parts) < 4 or not parts[0].isdigit() or "::" not in parts[-2]:
        return None
    return int(parts[0]), "/" + "/".join(parts[1:-2]), ros_type(parts[-2]), parts[-1]


def _mangle(name: str) -> str:
    return name.replace("/", "%") or "%"


def _unmangle(name: str) -> str:
    return name.replace("%", "/")


@dataclass(frozen=True)
class LivelinessToken:
    """A graph entity of rmw_zenoh (module docstring): ``kind`` ``MP`` / ``MS`` / ``NN`` /
    ``SS`` / ``SC``, its ``topic`` and ROS ``type`` (empty for a node), ``domain``."""

    domain: int
    kind: str
    topic: str
    type: str
    type_hash: str


def liveliness_token(domain: int, zid: str, entity: int, kind: str, node: str, topic: str,
                     ros: str, type_hash: str, qos: str = "::,10:,:,:,,") -> str:
    """The key expression of a publisher's (``kind`` ``MP``) or subscription's (``MS``)
    liveliness token, as rmw_zenoh declares it (node ``node`` in the root namespace)."""
    return "/".join([LIVELINESS_PREFIX, str(domain), zid, "0", str(entity), kind, "%", "%",
                     node, _mangle(topic), dds_type(ros), type_hash, qos])


def parse_liveliness(key: str) -> LivelinessToken | None:
    """A liveliness token's key expression -> :class:`LivelinessToken`; None when it is not
    one of rmw_zenoh's publisher or subscription tokens."""
    parts = key.split("/")
    if len(parts) < 12 or parts[0] != LIVELINESS_PREFIX or not parts[1].isdigit():
        return None
    kind = parts[5]
    if kind not in ("MP", "MS"):
        return None
    return LivelinessToken(int(parts[1]), kind, _unmangle(parts[9]), ros_type(parts[10]),
                           parts[11])


def bridge_key(namespace: str, topic: str) -> str:
    """zenoh-bridge-ros2dds's key expression of ``topic`` (module docstring)."""
    ns = namespace.strip("/")
    return f"{ns}/{topic.strip('/')}" if ns else topic.strip("/")


def bridge_liveliness(zid: str, key: str, ros: str, qos: str = ":::") -> str:
    """The liveliness token zenoh-bridge-ros2dds declares for a routed publisher of the key
    expression ``key`` and type ``ros`` (module docstring)."""
    return "/".join([LIVELINESS_PREFIX, zid, "MP", key.replace("/", "§"),
                     normalize_msgtype(ros).replace("/", "§"), qos])


def parse_bridge_liveliness(key: str, namespace: str = "/") -> LivelinessToken | None:
    """A zenoh-bridge-ros2dds publisher or subscriber token -> :class:`LivelinessToken`
    (domain 0, the topic without the bridge's namespace); None when it is not one."""
    parts = key.split("/")
    if len(parts) != 6 or parts[0] != LIVELINESS_PREFIX or parts[2] not in ("MP", "MS"):
        return None
    topic = "/" + parts[3].replace("§", "/")
    ns = namespace.rstrip("/")
    if ns:
        if not topic.startswith(ns + "/"):
            return None
        topic = topic[len(ns):]
    return LivelinessToken(0, parts[2], topic, ros_type(parts[4].replace("§", "/")), "")


def attachment(sequence: int, source_ns: int, gid: bytes) -> bytes:
    """rmw_zenoh's attachment of a message (module docstring)."""
    return _ATTACH.pack(sequence, source_ns) + bytes([len(gid)]) + gid


def attachment_time(data: bytes | None) -> int | None:
    """The source timestamp (ns) of rmw_zenoh's attachment; None when there is none."""
    if data is None or len(data) < _ATTACH.size:
        return None
    return _ATTACH.unpack_from(data)[1]


@functools.lru_cache(maxsize=8)
def standard_store(msg_path: tuple[str, ...] = ()) -> Typestore:
    """rosbags' type store of ROS 2 Humble's standard types and the events of the standard
    services (:mod:`fretc.logs.ros.standard_services`), or the ``.msg``/``.idl`` types of
    ``msg_path`` (``--msg-path``, :mod:`fretc.logs.ros.msg_path`) when given."""
    if msg_path:
        from fretc.logs.ros.msg_path import msg_path_typestore

        return msg_path_typestore(tuple(msg_path))
    from rosbags.typesys import Stores, get_typestore

    from fretc.logs.ros.standard_services import register_service_events

    store = get_typestore(Stores.ROS2_HUMBLE)
    register_service_events(store)  # the events of std_srvs' services (introspection)
    return store


def advertisement(cid: int, topic: str, ros: str, store: Typestore, expected: str | None = None
                  ) -> Advertised:
    """The :class:`~fretc.live.protocol.Advertised` of ``topic`` carrying CDR of ROS type ``ros``
    with the ``ros2msg`` definition ``store`` gives; an unreadable one (the watch then makes
    the topic's requirements ``error`` saying why) when ``store`` does not know the type or
    it is not ``expected`` (the bindings' ``[types]``)."""
    if expected and normal_type(expected) != normal_type(ros):
        return Advertised(cid, topic, "cdr", ros, "", "", unreadable=(
            f"{topic} carries {ros}, the bindings expect {expected}"))
    try:
        name = normalize_msgtype(ros)
        text = store.generate_msgdef(name, ros_version=2)[0]
    except Exception:  # a type the store lacks, or a name that is not a ROS type
        return Advertised(cid, topic, "cdr", ros, "", "", unreadable=(
            f"no definition of {ros} in ROS 2's standard types or the --msg-path folders"))
    return Advertised(cid, topic, "cdr", name, text, "ros2msg")


def normal_type(name: str) -> str:
    """A ROS type name in its normal form (``std_msgs/Bool`` -> ``std_msgs/msg/Bool``,
    rosbags' ``normalize_msgtype``); a name that is no ROS type name as it is."""
    try:
        return normalize_msgtype(name)
    except Exception:  # not a ROS type name
        return name


def cdr_clock_ns(payload: bytes) -> int | None:
    """The time of a CDR ``rosgraph_msgs/msg/Clock`` on ``/clock`` (:data:`CLOCK_TOPIC`):
    int32 sec and uint32 nanosec after the 4-byte encapsulation header, in ns since the
    epoch; None when the payload is too short."""
    if len(payload) < 12:
        return None
    little = payload[1] & 1
    sec = int.from_bytes(payload[4:8], "little" if little else "big", signed=True)
    nsec = int.from_bytes(payload[8:12], "little" if little else "big")
    return sec * 1_000_000_000 + nsec
