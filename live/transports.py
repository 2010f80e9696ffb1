"""The client of a watch's URL (one per transport, all feeding the same
:class:`~fretc.live.source.WatchSource` through an :class:`~fretc.live.events.EventQueue`):

* ``ws://``, ``wss://``: the Foxglove WebSocket protocol
  (:class:`~fretc.live.websocket.foxglove.FoxgloveClient`);
* ``rosbridge://``, ``rosbridge+wss://``: rosbridge v2
  (:class:`~fretc.live.websocket.rosbridge.RosbridgeClient`);
* ``dds://DOMAIN``: ROS 2's DDS mapping over Cyclone DDS
  (:class:`~fretc.live.dds.client.DdsClient`);
* ``zenoh://HOST:PORT``: rmw_zenoh's key expressions
  (:class:`~fretc.live.zenoh.client.ZenohClient`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, Protocol, TYPE_CHECKING

if TYPE_CHECKING:
    from fretc.live.websocket.session import WebSocketClient
    from fretc.live.dds.client import DdsClient
    from fretc.live.zenoh.client import ZenohClient

__all__ = ["make_client", "URL_SCHEMES", "ClientOptions"]

#: The URL schemes ``fretc watch`` speaks.
URL_SCHEMES = ("ws://", "wss://", "rosbridge://", "rosbridge+wss://", "dds://", "zenoh://")


class ClientOptions(Protocol):
    """What a client is made from: the fields of :class:`fretc.live.watch.WatchOptions` that
    name them (the URL, the reconnection delays in seconds, the topic types given on the
    command line, the ``--msg-path`` folders, the middleware's configuration file and the
    merge hold in seconds)."""

    @property
    def url(self) -> str:
        """The server or domain to watch (``ws://``, ``rosbridge://``, ``dds://``, ``zenoh://``)."""

    @property
    def backoff(self) -> float:
        """Seconds before the first reconnection."""

    @property
    def max_backoff(self) -> float:
        """Seconds between reconnections at most (the backoff doubles up to it)."""

    @property
    def types(self) -> dict[str, str] | None:
        """Topic -> ROS message type given on the command line (``--topic-type``)."""

    @property
    def msg_path(self) -> tuple[str, ...]:
        """Folders of the robot's own ``.msg``/``.idl`` files (``--msg-path``)."""

    @property
    def config(self) -> str | None:
        """The middleware's configuration file (``--dds-config``, ``--zenoh-config``)."""

    @property
    def merge_hold(self) -> float:
        """Seconds a message is held to be merged into log-time order (DDS, Zenoh)."""


def make_client(options: ClientOptions, wanted: Callable[[str], bool],
                types: dict[str, str] | None = None, topics: Iterable[str] = ()
                ) -> WebSocketClient | DdsClient | ZenohClient:
    """The client for ``options.url`` (a :class:`~fretc.live.watch.WatchOptions`:
    :class:`ClientOptions`): ``wanted`` topic -> bool; ``types`` the bindings' ``[types]``
    (overridden by ``options.types``); ``topics`` the bound topics (the DDS and Zenoh clients
    subscribe to exactly these).

    Raises:
        MissingDependency: the transport's package is not installed (the message names the
            install hint); ValueError: a DDS or Zenoh URL of the wrong form.
    """
    kw: dict[str, Any] = {"backoff": options.backoff, "max_backoff": options.max_backoff}
    given = dict(types or {})
    given.update(options.types or {})
    url = options.url
    if url.startswith("zenoh://"):
        from fretc.live.zenoh.client import ZenohClient

        return ZenohClient(url, wanted, topics=topics, types=given,
                           msg_path=options.msg_path, config_file=options.config,
                           merge_hold=options.merge_hold)
    if url.startswith("dds://"):
        from fretc.live.dds.client import DdsClient

        return DdsClient(url, wanted, topics=topics, types=given, msg_path=options.msg_path,
                         config_file=options.config, merge_hold=options.merge_hold)
    from fretc.live.websocket.foxglove import FoxgloveClient
    from fretc.live.websocket.session import require_websockets

    require_websockets()
    if url.startswith(("rosbridge://", "rosbridge+wss://")):
        from fretc.live.websocket.rosbridge import RosbridgeClient  # lazy: numpy's message building

        return RosbridgeClient(url, wanted, types=given, msg_path=options.msg_path, **kw)
    return FoxgloveClient(url, wanted, **kw)
