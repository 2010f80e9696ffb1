"""The progress display of ``fretc audit`` on a terminal: one bar for the logs done, one per
log being read (rich's ``Progress``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from fretc.audit.verdict import LogAudit
from fretc.reports.terminal import short_log_name

if TYPE_CHECKING:
    from rich.progress import TaskID

__all__ = ["AuditProgress"]


class AuditProgress:
    """A rich progress display: one bar for the logs done, one per log being read (fraction
    of its log time). Used as the ``progress`` object of :func:`fretc.audit.audit_logs`."""

    def __init__(self, console, total: int):
        # lazy: only on a terminal (start-up time of the other runs)
        from rich.progress import (BarColumn, Progress, TaskProgressColumn, TextColumn,
                                   TimeElapsedColumn)

        self.progress = Progress(TextColumn("{task.description}", markup=False), BarColumn(),
                                 TaskProgressColumn(), TimeElapsedColumn(), console=console,
                                 transient=True)
        self.total = self.progress.add_task("logs", total=total)
        self.tasks: dict[int, TaskID] = {}

    def __enter__(self):
        self.progress.start()
        return self

    def __exit__(self, *exc):
        self.progress.stop()

    def start(self, index: int, path: str) -> None:
        """A progress bar for log ``index`` (its file name shown)."""
        self.tasks[index] = self.progress.add_task(short_log_name(path), total=1.0)

    def update(self, index: int, fraction: float) -> None:
        """Log ``index`` read to ``fraction`` (0 to 1)."""
        task = self.tasks.get(index)
        if task is not None:
            self.progress.update(task, completed=fraction)

    def done(self, index: int, la: LogAudit) -> None:
        """Log ``index`` audited: its bar removed, the overall bar advanced."""
        task = self.tasks.pop(index, None)
        if task is not None:
            self.progress.remove_task(task)
        self.progress.advance(self.total)
