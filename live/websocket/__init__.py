"""The WebSocket transports of ``fretc watch`` and the server of ``fretc replay --serve``:
the Foxglove WebSocket protocol (``ws://``, the protocol of ``foxglove_bridge`` and
``foxglove-sdk``) and rosbridge v2 (``rosbridge://``).

Modules: :mod:`.session` the connection kept in a thread, retried with backoff, bounded (the
base of both clients); :mod:`.foxglove` the Foxglove client; :mod:`.rosbridge` the rosbridge
client (JSON messages to CDR); :mod:`.serve` the Foxglove server that replays a log or serves
the simulator.

May import: the layers before ``fretc.live`` and :mod:`fretc.live.protocol`,
:mod:`fretc.live.events`; not the other transports' subpackages.
"""
