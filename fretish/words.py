"""FRETish's reserved words and letters (lexical facts shared by the parser, its error
messages and the printers that decide when a name must be quoted)."""

from __future__ import annotations

__all__ = ["RESERVED_WORDS", "RESERVED_LETTERS", "UNIT_TOKENS"]

#: FRETish keywords (case-insensitive); none of them can name a variable (FRET 3.x
#: ``Requirement.g4`` lexer rules). Unit words also take their plural and short forms.
RESERVED_WORDS = frozenset("""
    after always and at before during eventually except false finally first for hour hours
    if immediately in initially is last microsec microsecs microsecond microseconds
    millisec millisecs millisecond milliseconds minute minutes mod mode never next not
    occurrence of only or previous probability same satisfy sec secs second seconds shall
    the then tick ticks timepoint true unless until upon what when whenever where while
    with within xor""".split())
#: Operators of FRET's printed formulas (../shared/fretish/README.md section 6); reserved,
#: case-sensitive.
RESERVED_LETTERS = frozenset("XFGUVYZHOST")

#: The grammar's unit terminals (``grammar.lark``) -> the :class:`fretish.ast.Duration`
#: unit.
UNIT_TOKENS = {"TICK": "ticks", "MICROSECOND": "microseconds", "MILLISECOND": "milliseconds",
               "SECOND": "seconds", "MINUTE": "minutes", "HOUR": "hours"}
