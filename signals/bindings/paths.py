"""Text of message paths in Foxglove's message path syntax, as bindings and ``fretc inspect``
print them: a topic bare when it is a plain ROS name (``/a/b_c``), else quoted
(``"ORB-SLAM"``, ``"groundtruth"``); string literals in double quotes with ``\\"`` and
``\\\\`` escaped (Foxglove's message path syntax, docs.foxglove.dev "Message path syntax").
"""

from __future__ import annotations

import re

__all__ = ["PLAIN_TOPIC", "topic_text", "quote", "unquote", "topic_name"]

#: A topic written without quotes: ``/`` and name characters, as grammar.lark's TOPIC.
PLAIN_TOPIC = re.compile(r"(/[A-Za-z0-9_]+)+\Z")
_ESCAPE = re.compile(r"\\(.)")


def quote(text: str) -> str:
    """``text`` as a double-quoted string literal of a binding (``\\`` and ``"`` escaped)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def unquote(token: str) -> str:
    """The text of a string literal token (``"a\\"b"`` or ``'a'``): quotes removed, a
    backslash keeps the character after it."""
    return _ESCAPE.sub(r"\1", token[1:-1])


def topic_text(topic: str) -> str:
    """A topic as it is written in a binding: bare when :data:`PLAIN_TOPIC` matches, else
    quoted (a topic without a leading ``/`` or with ``-``, ``.``, spaces)."""
    return topic if PLAIN_TOPIC.match(topic) else quote(topic)


def topic_name(text: str) -> str | None:
    """A topic named as a user copies it from ``fretc inspect`` (a tick topic): a ROS name
    (``/scan``), a flight log's topic without a leading ``/`` (``vehicle_local_position``,
    ``sensor_accel/1``, ``GPS``), or either in double quotes as a binding writes it
    (``"vehicle_local_position"``); None when it cannot be a topic name (empty, blank, a
    control character, unbalanced quotes)."""
    if not isinstance(text, str):
        return None
    name = text.strip()
    if len(name) >= 2 and name[0] == name[-1] == '"':
        name = unquote(name)
    elif '"' in name:
        return None
    if not name or name != name.strip() or any(ord(c) < 32 or ord(c) == 127 for c in name):
        return None
    return name
