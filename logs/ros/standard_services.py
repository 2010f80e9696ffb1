"""The services of ROS 2's standard interface packages, for topics that carry their events
but no definition: a live ROS 2 graph (``fretc watch dds://``) names a service event's type
(``std_srvs/srv/SetBool_Event``, service introspection, ROS 2 Iron and later) and nothing
more, and rosbags' type stores hold messages, not services.

:data:`SERVICES` holds the request and response of each (the ``.srv`` texts of ROS 2 Jazzy's
``std_srvs`` and ``example_interfaces``); :func:`register_service_events` adds each event
type to a type store, built as rosbag2 builds it (:func:`fretc.logs.decoding.service_event_text`).
A project's own services come from ``--msg-path`` (their ``.srv`` files).
"""

from __future__ import annotations

from typing import Any

from fretc.logs.decoding import service_event_text

__all__ = ["SERVICES", "register_service_events"]

#: service type -> its ``.srv`` text (request ``---`` response)
SERVICES = {
    "std_srvs/srv/Empty": "---\n",
    "std_srvs/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "std_srvs/srv/Trigger": "---\nbool success\nstring message\n",
    "example_interfaces/srv/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "example_interfaces/srv/SetBool": "bool data\n---\nbool success\nstring message\n",
    "example_interfaces/srv/Trigger": "---\nbool success\nstring message\n",
}


def register_service_events(store: Any) -> None:
    """Add the event type ``pkg/srv/Name_Event`` of every service of :data:`SERVICES` (and
    its request and response) to the rosbags type store ``store``, when it lacks it."""
    from rosbags.typesys import get_types_from_msg

    for service, text in SERVICES.items():
        event = service + "_Event"
        if event in store.fielddefs:
            continue
        full = service_event_text(event, text)
        types = get_types_from_msg(full, event)
        store.register({k: v for k, v in types.items() if k not in store.fielddefs})
