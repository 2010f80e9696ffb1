"""Many logs: audited one after another or in worker processes, on a Ray cluster, and the
statistics over their runs.

Modules: :mod:`.workers` :func:`~fretc.audit.fleet.workers.audit_logs` (``-j N``: worker
processes, results in input order); :mod:`.ray` and :mod:`.ray_driver` the fleet on Ray
(``fretc audit --ray``: one task per log, the driver in a process of its own);
:mod:`.statistics` per requirement the runs of each verdict and the statistical verdict of
``with probability`` requirements (each log's trials from :mod:`fretc.audit.trials`), with
:mod:`.intervals` (exact binomial intervals and sequential decisions, shared with ``fretc
estimate``).

May import: the layers before the audit and every other part of :mod:`fretc.audit` (a fleet
runs the audit of one log, :func:`fretc.audit.log.audit_log`, on each); nothing in the
audit outside this subpackage imports it but :mod:`fretc.audit.verdict` (the exit code of a
statistical verdict) and the package's re-export of :func:`audit_logs`.
"""
