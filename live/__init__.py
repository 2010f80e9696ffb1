"""Live robots: ``fretc watch`` (:mod:`.watch` the session, :mod:`.source` the watched
messages as a log source, :mod:`.columns` the columns kept while watching, :mod:`.checks` what
is checked before a requirement steps, :mod:`.entities` and :mod:`.entity_events` per-entity
requirements, :mod:`.record` its recording, :mod:`.diagnostics` its verdicts as
``/diagnostics``) over any of its transports, each in a subpackage: :mod:`.websocket` (the
Foxglove WebSocket protocol and rosbridge), :mod:`.dds` and :mod:`.zenoh` (ROS 2's own
middlewares). What every transport hands the watch is in :mod:`.protocol` (the events),
:mod:`.events` (the bounded queue), :mod:`.merge` (several subscriptions in log-time order)
and :mod:`.absence` (spans without a publisher); :mod:`.transports` picks the client of a
URL; :mod:`.ros2_names` holds ROS 2's naming rules on DDS and Zenoh. The transports'
servers (``fretc replay --serve``, ``python -m fretc.sim serve``) sit beside their clients.

A watch is a live audit: it samples, judges and reports with the audit's own steps
(:mod:`fretc.audit`), so this package comes after it in the pipeline."""
