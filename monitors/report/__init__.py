"""What an audit found and how it is shown: the verdicts and the audit JSON (:mod:`.model`),
the terminal summary (:mod:`.terminal`), JUnit XML (:mod:`.junit`), the traceability report
(``fretc report``: :mod:`.write` with :mod:`.files`, :mod:`.context`, :mod:`.trace`,
:mod:`.verdicts`, :mod:`.render`; timelines in :mod:`.timeline` and :mod:`.timeline_layout`)
and verdicts written back into MCAP copies (:mod:`.annotate`)."""
