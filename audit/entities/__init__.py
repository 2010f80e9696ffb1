"""Requirements judged per entity of a log (docs/bindings.md, "One verdict per entity"): a
requirement whose variables read an entity of the binding file's ``[entities]`` table
(``$track``) gets one verdict per entity and one over all of them.

Modules: :mod:`.log` the per-entity requirements of one log audited (the entry point of
:func:`fretc.audit.log.audit_log`); :mod:`.kinds` what an ``[entities]`` name is made of;
:mod:`.read` every entity in one read of the log, :mod:`.rows` its per-entity variables over
(message, entity) rows by numpy, :mod:`.runs` the ticks of a clock without plain variables
as runs; :mod:`.columns` an entity's columns and all of them end to end; :mod:`.batch` the
entities judged at once; :mod:`.summary` the verdict over all entities.

May import: the layers before the audit (``fretc.common`` ... ``fretc.check``) and the
audit's own steps outside its subpackages (:mod:`fretc.audit.passes`,
:mod:`fretc.audit.finalize`, :mod:`fretc.audit.gaps`, :mod:`fretc.audit.verdict`, ...); not
:mod:`fretc.audit.sampled` nor :mod:`fretc.audit.fleet`, which use it.
"""
