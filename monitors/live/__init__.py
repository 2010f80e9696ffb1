"""Live robots: ``fretc watch`` over the Foxglove WebSocket protocol (:mod:`.watch` the
session, :mod:`.client` the protocol client, :mod:`.source` messages as a log source) and
the server that ``fretc replay --serve`` and ``python -m sim serve`` run (:mod:`.serve`)."""
