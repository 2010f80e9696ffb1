"""CSV traces of FRET variables: a header row of variable names, one row per tick, with the
marks of unknown ticks and cuts, and the clocks of a sampled trace (``fretc audit
--write-csv``).

Modules: :mod:`.source` :class:`~fretc.logs.csv.source.CsvSource`; :mod:`.read` the one read
of its rows (checked, kept as compact columns); :mod:`.clocks` a sampled trace's clocks read
in one pass.

May import: ``fretc.common`` and :mod:`fretc.logs.base`; not the other formats' subpackages.
"""
