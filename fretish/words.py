"""FRETish's reserved words and letters (lexical facts shared by the parser, its error
messages and the printers that decide when a name must be quoted)."""

from __future__ import annotations

__all__ = ["RESERVED_WORDS", "RESERVED_LETTERS", "UNIT_TOKENS", "FRET_RESERVED"]

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

#: The grammar's unit terminals (``grammar.lark``) -> the :class:`fretc.fretish.ast.Duration`
#: unit.
UNIT_TOKENS = {"TICK": "ticks", "MICROSECOND": "microseconds", "MILLISECOND": "milliseconds",
               "SECOND": "seconds", "MINUTE": "minutes", "HOUR": "hours"}

#: Names FRET refuses in a requirement's expressions (../shared/fretish/README.md section 5):
#: NuSMV's reserved words less ``TRUE FALSE xor next mod of in``, and R2U2's. Case
#: sensitive, whole words of the expression after FRET's special-character replacement, so
#: only a plain name equal to one of them can match (``a.count`` prints ``a_DOT_count``).
FRET_RESERVED = frozenset("""
    MODULE DEFINE MDEFINE CONSTANTS VAR IVAR FROZENVAR INIT TRANS INVAR SPEC CTLSPEC LTLSPEC
    PSLSPEC COMPUTE NAME INVARSPEC FAIRNESS JUSTICE COMPASSION ISA ASSIGN CONSTRAINT SIMPWFF
    CTLWFF LTLWFF PSLWFF COMPWFF IN MIN MAX MIRROR PRED PREDICATES process array boolean
    integer real word word1 bool signed unsigned extend resize sizeof uwconst swconst EX AX EF
    AF EG AG E F O G H X Y Z A U S V T BU EBF ABF EBG ABG case esac init union xnor self count
    abs max min
    FTSPEC PTSPEC INPUT STRUCT ENUM int float R""".split())
