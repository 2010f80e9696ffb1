"""Requirements judged per entity of a log (docs/bindings.md, "One verdict per entity"): a
requirement whose variables read an entity of the binding file's ``[entities]`` table
(``$track``) gets one verdict per entity and one over all of them.

May import: the layers before the audit (``fretc.common`` ... ``fretc.check``) and the
audit's own steps outside its subpackages (:mod:`fretc.audit.passes`,
:mod:`fretc.audit.finalize`, :mod:`fretc.audit.gaps`, :mod:`fretc.audit.verdict`, ...); not
:mod:`fretc.audit.sampled` nor :mod:`fretc.audit.fleet`, which use it.

Design notes: ARCHITECTURE.md, `audit/entities/__init__.py`."""
