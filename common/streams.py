"""Message streams: the messages of one topic that pass a FoxQL filter written right after
the topic (``/track{id==3}.x``, docs/bindings.md "FoxQL: paths copied from Foxglove").

Inside the sampling such a stream is read as a topic of its own, named by the topic and its
filters as written (``/track{id==3}``): its held message is the newest message of the topic
that passes the filters, and a message that fails them is, for the bindings that read the
stream, as if it were not published. Where the bindings meet the log (which topics to read,
their gaps, damage and live subscriptions) a stream stands for its topic
(:func:`base_topic`). ROS names have no braces, so a name ending in ``}`` with a ``{`` is a
stream's.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["base_topic", "log_topics", "is_stream"]


def is_stream(name: str) -> bool:
    """Whether ``name`` is a stream's name (``/track{id==3}``) rather than a topic's."""
    return name.endswith("}") and "{" in name


def base_topic(name: str) -> str:
    """The topic a stream reads (``/track{id==3}`` -> ``/track``); a topic's name as it is."""
    return name[:name.index("{")] if is_stream(name) else name


def log_topics(names: Iterable[str]) -> set[str]:
    """The topics of the log that ``names`` (topics and streams) read."""
    return {base_topic(n) for n in names}
