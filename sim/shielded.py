"""The simulated robot with a generated shield as its Safety System (``python -m fretc.sim
record --safety shield:DIR``): the shield of ``fretc shield --emit python -b BINDINGS -o DIR``
takes the place of the hand-written SIF and ``cmd_vel_interceptor`` (:mod:`fretc.sim.safety`).

Each 100 ms tick, at the scan's log time (so that the audit's tick sees the scan and the
shield's answer together, as it sees the hand-written SIF's): the shield reads the held
``/scan`` (and its age) through the bindings, takes the SRAS's latest ``/cmd_vel`` as the
proposal for ``/cmd_vel_filtered``, and publishes ``/cmd_vel_filtered`` and
``/gwendolen_control`` (:class:`fretc.shield.messages.MessageShield`). Every override is kept
with its reasons (:attr:`ShieldedSafety.overrides`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fretc.shield.messages import MessageShield, ShieldInputError, proposals_of
from fretc.shield.replay import ReplayError, load_folder
from fretc.signals.bindings.files import load_bindings

__all__ = ["ShieldedSafety", "SHIELD_PREFIX", "DEFAULT_PROPOSALS"]

#: the ``--safety`` value that names a shield folder
SHIELD_PREFIX = "shield:"
#: the proposal topics when the bindings carry no ``[shield] proposals`` (Safe-ROS's)
DEFAULT_PROPOSALS = {"/cmd_vel_filtered": "/cmd_vel"}


class ShieldedSafety:
    """The shield written in ``folder`` (one ``*_shield.py`` and the ``*.bindings.toml`` it was
    built with) between the simulated robot's topics (module docstring).

    Raises:
        ValueError: the folder does not hold exactly one of each, or its module does not
            load or defines no ``Shield`` (:func:`fretc.shield.replay.load_folder`'s
            reasons)."""

    def __init__(self, folder: str | Path, factory: Any = None):
        try:
            loaded = load_folder(folder)
        except ReplayError as exc:
            raise ValueError(str(exc)) from None
        self.path = loaded.module
        self.runtime = loaded.shield_class()
        self.bindings_file = loaded.bindings_file
        self.bindings = load_bindings(loaded.bindings_file)
        self.proposals = proposals_of(loaded.bindings_file) or dict(DEFAULT_PROPOSALS)
        self.factory = factory
        self.shield: MessageShield | None = None
        #: (sim time s, reasons, changed output atoms) of every override
        self.overrides: list[tuple[float, tuple[str, ...], tuple[str, ...]]] = []
        self.ticks = 0
        #: (sim time s, ids) of each assumption of the environment when it first broke
        self.broken: list[tuple[float, tuple[str, ...]]] = []

    def start(self, factory: Any) -> None:
        """Bind to a recorder's message factory (the messages' types) and reset the shield."""
        self.factory = factory
        self.runtime.reset()
        self.overrides, self.ticks, self.broken = [], 0, []
        makers = {"/cmd_vel_filtered": lambda: factory.twist(0.0, 0.0),
                  "/ground_truth/clearance": lambda: factory.float64(0.0),
                  "/cmd_vel": lambda: factory.twist(0.0, 0.0),
                  "/gwendolen_control": lambda: factory.bool(False)}

        def make(topic: str) -> Any:
            if topic not in makers:
                raise ValueError(f"the simulator publishes no {topic}")
            return makers[topic]()

        self.shield = MessageShield(self.runtime, self.bindings, self.proposals, make)

    def restart(self) -> None:
        """The shield's node came back after a crash (the ``safety_restart`` fault of
        :mod:`fretc.sim.faults`): its state reset to the initial one and every message it
        held forgotten, as a node that starts again; its overrides, ticks and broken
        assumptions so far are kept (they are the run's)."""
        assert self.factory is not None and self.shield is not None
        kept = (self.overrides, self.ticks, self.broken)
        self.start(self.factory)
        self.overrides, self.ticks, self.broken = kept

    def hear(self, topic: str, message: Any, log_time_ns: int) -> None:
        """A message the robot published (inputs, and the SRAS's proposals)."""
        assert self.shield is not None
        self.shield.hear(topic, message, log_time_ns)

    def tick(self, t: float, log_time_ns: int) -> list[tuple[str, Any]]:
        """The messages the shield publishes at this tick (none while an input cannot be read
        yet: before the first scan)."""
        assert self.shield is not None
        try:
            d, msgs = self.shield.tick(log_time_ns)
        except ShieldInputError:
            return []
        self.ticks += 1
        if d.overridden:
            self.overrides.append((t, d.reasons, d.changed))
        gone = tuple(a for a in getattr(d, "broken", ()) if all(a not in b for _t, b in
                                                                 self.broken))
        if gone:
            self.broken.append((t, gone))
        return msgs
