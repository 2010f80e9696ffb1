"""Live robots: ``fretc watch`` over the Foxglove WebSocket protocol (:mod:`.watch` the
session, :mod:`.client` the protocol client, :mod:`.source` messages as a log source,
:mod:`.columns` the columns kept while watching; :mod:`.rosbridge` the rosbridge client) and
the server that ``fretc replay --serve`` and ``python -m fretc.sim serve`` run (:mod:`.serve`).

A watch is a live audit: it samples, judges and reports with the audit's own steps
(:mod:`fretc.audit`), so this package comes after it in the pipeline."""
