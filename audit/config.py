"""What an audit needs besides the logs (:class:`AuditConfig`), and the error of input it
cannot start with (:class:`AuditInputError`)."""

from __future__ import annotations

from dataclasses import dataclass

from fretc.common.problems import FretcInputError

__all__ = ["AuditConfig", "AuditInputError"]


class AuditInputError(FretcInputError):
    """Input the audit cannot start with (exit code 2): unreadable requirement or binding
    files, conflicting bindings, bad options, no logs. The message names the file."""


@dataclass(frozen=True)
class AuditConfig:
    """Everything an audit needs besides the logs; plain values (picklable for workers).

    Attributes:
        requirements: requirement files or folders (``.fret``, FRET JSON exports).
        bindings: binding files (TOML); None: discover ``*.bindings.toml`` next to the
            requirements (:func:`discover_bindings`).
        inline: ``NAME=EXPR`` bindings (``--bind``), added last.
        tick_period: override of the bindings' tick (``"100 ms"``); ``tick_topic``: one tick
            per message of this topic; ``time_base``: ``"log"`` or ``"header"``.
        window: ticks of values shown on each side of the trigger and the violation.
        msg_path: folders of ``.msg``/``.idl`` files for types a log does not carry
            (``--msg-path``, :mod:`fretc.logs.ros.msg_path`).
        text_attribute: the attribute of ReqIF / Doorstop requirements holding the FRETish
            text (``--text-attribute``; None: :mod:`fretc.fretish.sources`' default).
        bridge_gaps_ns: ``--bridge-gaps``: gaps of a log shorter than this (ns) are bridged
            (the value before held over them, each listed) instead of leaving their ticks
            unknown (:mod:`fretc.audit.gaps`); None bridges none (the default).
        max_entities: ``--max-entities``: entities of one per-entity requirement judged per
            log (None: :data:`fretc.audit.entities.log.DEFAULT_MAX_ENTITIES`); past it, an error
            verdict says how to raise it.
        allowance: ``--allowance TOPIC=DURATION``: topic -> ns its messages are read
            earlier (a reaction allowance, :mod:`fretc.logs.allowance`), over the binding
            files' ``[audit] allowance`` for the same topic; ``()`` none.
    """

    requirements: tuple[str, ...]
    bindings: tuple[str, ...] | None = None
    inline: tuple[str, ...] = ()
    tick_period: str | None = None
    tick_topic: str | None = None
    time_base: str | None = None
    window: int = 5
    select_logs: bool = True
    msg_path: tuple[str, ...] = ()
    text_attribute: str | None = None
    bridge_gaps_ns: int | None = None
    max_entities: int | None = None
    allowance: tuple[tuple[str, int], ...] = ()

