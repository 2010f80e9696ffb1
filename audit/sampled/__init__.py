"""A log's FRET variables as the audit judged them, as a sampled CSV trace (``fretc audit
--write-csv DIR``), and the audit of such a trace clock by clock.

Modules: :mod:`.csv` the trace written (each requirement's own clock, unknown ticks marked);
:mod:`.clock` one clock of it, its ticks and cells; :mod:`.entities` the per-entity
requirements written each entity on its own clock; :mod:`.audit` the audit of such a trace
(its ``# fretc clock N`` lines read back).

May import: the layers before the audit, the audit's own steps (:mod:`fretc.audit.log`,
:mod:`fretc.audit.plan`, :mod:`fretc.audit.passes`, :mod:`fretc.audit.verdict`, ...) and
:mod:`fretc.audit.entities`; not :mod:`fretc.audit.fleet`.
"""
