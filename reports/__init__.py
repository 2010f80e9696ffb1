"""How an audit's verdicts are shown: the terminal summary (:mod:`.terminal`), JUnit XML
(:mod:`.junit`), the traceability report (``fretc report``: :mod:`.write` with :mod:`.files`,
:mod:`.context`, :mod:`.trace`, :mod:`.verdicts`, :mod:`.render`; timelines in
:mod:`.timeline` and :mod:`.timeline_layout`, the margin plot in :mod:`.margin`) and the
report of ``fretc falsify`` (:mod:`.falsify`).

The last step of the pipeline: every module here reads the audit's verdict model
(:mod:`fretc.audit.verdict`) and nothing but the commands (``fretc/``) imports this package
(tests/test_architecture.py)."""
