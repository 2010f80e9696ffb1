"""The tool qualification kit (docs/qualification/): fretc's tool operational requirements
and known problems, each in one TOML file of this package (:mod:`.catalogue` reads, checks
and renders them), and the validation suite of ``fretc qualify`` (:mod:`.suite`): checks of
the installed fretc against a reference evaluator of FRET's semantics (:mod:`.reference`)
and the documented behaviour (:mod:`.checks`, :mod:`.checks_audit`), a mutation run of
seeded faults (:mod:`.faults`), and its report (:mod:`.environment`, :mod:`.report`,
:mod:`.kit`).

May import every package before it (it validates the whole pipeline) and
:mod:`fretc.reports` (the audit document's schema); nothing but :mod:`fretc.cli` imports it.
"""
