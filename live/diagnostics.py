"""``fretc watch --publish-diagnostics``: the watch's verdicts back on the robot's bus as a
``diagnostic_msgs/DiagnosticArray`` on ``/diagnostics`` (REP 107's diagnostics topic, read by
``diagnostic_aggregator``, ``rqt_robot_monitor`` and Foxglove), over the transport watched
(DDS or Zenoh), once a second and on every change of a verdict.

Design notes: ARCHITECTURE.md, `live/diagnostics.py`."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, TYPE_CHECKING

from fretc.live.ros2_names import standard_store

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore
    from fretc.audit.verdict import LogAudit
    from fretc.live.watch import Watch

__all__ = ["DIAGNOSTICS_TOPIC", "DIAGNOSTIC_ARRAY", "Status", "live_statuses",
           "final_statuses", "diagnostic_array", "DiagnosticsPublisher", "LEVELS"]

DIAGNOSTICS_TOPIC = "/diagnostics"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
#: verdict -> DiagnosticStatus level (OK 0, ERROR 2, STALE 3; diagnostic_msgs' constants)
LEVELS = {"satisfied": 0, "vacuous": 0, "pending": 0, "violated": 2, "error": 2, "unknown": 3}

#: (requirement id, verdict, first violation s or None, robustness or None, text)
Status = tuple[str, str, float | None, float | None, str]


def live_statuses(watch: Watch) -> list[Status]:
    """The statuses of a running :class:`~fretc.live.watch.Watch` from its live state: violated
    once an obligation failed or the LTL3 verdict is violated; satisfied when the LTL3
    verdict is; unknown before any tick; pending otherwise."""
    out: list[Status] = []
    for r in watch.plan.requirements:
        st = watch.live[r.index]
        first = None
        if st.error is not None:
            verdict = "error"
        elif st.status == "violated" or st.violations or st.first_violation is not None:
            verdict = "violated"
            times = watch.tick_times(r.index)
            if st.first_violation is not None and st.first_violation < len(times) \
                    and watch.start_time is not None:
                first = (int(times[st.first_violation]) - watch.start_time) / 1e9
        elif st.status == "satisfied":
            verdict = "satisfied"
        elif st.pt is None:
            verdict = "unknown"
        else:
            verdict = "pending"
        out.append((r.id, verdict, first, None, r.text))
    return out


def final_statuses(la: LogAudit, start_ns: int | None) -> list[Status]:
    """The statuses of the final verdicts of a watch's :class:`~fretc.audit.verdict.LogAudit`."""
    out = []
    for v in la.verdicts:
        fv = v.first_violation
        first = None if fv is None or start_ns is None else (fv.at.time_ns - start_ns) / 1e9
        out.append((v.requirement, v.verdict, first, v.robustness, v.text))
    return out


def diagnostic_array(statuses: list[Status], stamp_ns: int, store: Typestore | None = None
                     ) -> bytes:
    """The CDR bytes (with header) of a ``diagnostic_msgs/msg/DiagnosticArray`` of
    ``statuses`` (module docstring), stamped ``stamp_ns``."""
    store = store if store is not None else standard_store()
    T = store.types
    kv = T["diagnostic_msgs/msg/KeyValue"]
    items = []
    for rid, verdict, first, rob, text in statuses:
        values = [kv(key="verdict", value=verdict),
                  kv(key="first_violation_s", value="" if first is None else f"{first:.3f}"),
                  kv(key="robustness", value="" if rob is None else f"{rob:.6g}"),
                  kv(key="text", value=text)]
        items.append(T["diagnostic_msgs/msg/DiagnosticStatus"](
            level=LEVELS.get(verdict, 3), name=f"fretc: {rid}", message=verdict,
            hardware_id="fretc", values=values))
    stamp = T["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="")
    msg = T[DIAGNOSTIC_ARRAY](header=header, status=items)
    return bytes(store.serialize_cdr(msg, DIAGNOSTIC_ARRAY))


class DiagnosticsPublisher:
    """Publish a watch's verdicts on ``/diagnostics`` once a second and on every change.

    Args:
        watch: the :class:`~fretc.live.watch.Watch`.
        open_server: () -> a server with ``channel``/``log``/``stop`` (a
            :class:`~fretc.live.dds.serve.DdsServer` or :class:`~fretc.live.zenoh.serve.ZenohServer`
            on the watched transport), called once the watch is connected.
        period: seconds between two arrays when nothing changes (1 Hz).

    :meth:`changed` (thread-safe) asks for an array now; :meth:`finish` publishes the final
    verdicts and stops.
    """

    def __init__(self, watch, open_server: Callable[[], object], period: float = 1.0) -> None:
        self.watch = watch
        self.open_server = open_server
        self.period = period
        self.sent = 0
        self._server: Any = None  # the server the statuses are published on
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._last: list[Status] | None = None
        self._thread = threading.Thread(target=self._run, daemon=True,
                                        name="fretc-diagnostics")

    def start(self) -> DiagnosticsPublisher:
        """Start the publishing thread."""
        self._thread.start()
        return self

    def changed(self) -> None:
        """A verdict may have changed: publish at once."""
        self._wake.set()

    def _publish(self, statuses: list[Status]) -> None:
        if self._server is None:
            self._server = self.open_server()
            text = store_text()
            self._server.channel(DIAGNOSTICS_TOPIC, "cdr", DIAGNOSTIC_ARRAY, "ros2msg",
                                 text.encode("utf-8"))
        last = self.watch.source._last_time
        self._server.log(DIAGNOSTICS_TOPIC, diagnostic_array(statuses, last or time.time_ns()),
                         last or time.time_ns())
        self._last = statuses
        self.sent += 1

    def _run(self) -> None:
        src = self.watch.source
        while not self._stop.is_set():
            self._wake.wait(self.period)
            self._wake.clear()
            if self._stop.is_set() or not src.ever_connected:
                continue
            try:
                self._publish(live_statuses(self.watch))
            except Exception:  # diagnostics never stop the watch; the next tick retries
                continue

    def finish(self, la: LogAudit) -> None:
        """Publish the final verdicts of ``la`` and close the server."""
        self._stop.set()
        self._wake.set()
        self._thread.join(5)
        try:
            if self.watch.source.ever_connected:
                self._publish(final_statuses(la, self.watch.start_time))
                time.sleep(0.3)  # let it leave before the writer goes
        finally:
            if self._server is not None:
                self._server.stop()


def store_text() -> str:
    """The ``ros2msg`` definition of ``diagnostic_msgs/msg/DiagnosticArray``."""
    return standard_store().generate_msgdef(DIAGNOSTIC_ARRAY, ros_version=2)[0]
