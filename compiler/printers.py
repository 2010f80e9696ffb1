"""Printers of the formula IR.

* :func:`to_smv` - FRET's own SMV-flavoured syntax, so our formulas read next to FRET's:
  every binary operation and every unary operator application in parentheses,
  ``! & | xor -> <->``, ``X F G U V``, ``Y Z O H S T``, bounds ``[l,h]``, ``TRUE FALSE LAST``,
  identifiers mangled as FRET does (``a.b`` -> ``a_DOT_b``, ``x%`` -> ``x_PRC_``).
* :func:`to_spot` - Spot's LTL syntax (``R`` for release, ``F[l..h]``), for ft and ft_inf;
  atoms that are not plain identifiers (comparisons, calls, derived past atoms, ``LAST``)
  become double-quoted atomic propositions. Spot has no past operators: a pt formula raises
  ``ValueError``.
* :func:`expr_text` - a FRETish AST expression in FRET's printed form (for derived atoms;
  a stream read as a since, :mod:`fretc.fretish.fret_since`, prints ``(a S c)``).
"""

from __future__ import annotations

import functools
import re

from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE, stream_name
from fretc.fretish.words import FRET_RESERVED, RESERVED_LETTERS, RESERVED_WORDS

from fretc.compiler.ir import Node, name_of

#: FRET's names for the special characters of identifiers (../shared/fretish/README.md section
#: 6b, "Names"); each prints as ``_XXX_``.
FRET_CHAR_NAMES = {
    ".": "DOT", "%": "PRC", "#": "HSH", "$": "DOL", "&": "AMP", "@": "ATS", "!": "BNG",
    "?": "QUS", "-": "HYP", "*": "AST", "=": "EQU", "^": "CRT", " ": "SPC", "+": "PLS",
    ";": "SEM", ":": "CLN", ",": "CMA", "/": "FSL", "\\": "BSL", "|": "VBR", "~": "TLD",
    "<": "LAN", ">": "RAN", "(": "LPR", ")": "RPR", "{": "LCB", "}": "RCB", "[": "LSQ",
    "]": "RSQ", "'": "SQT", '"': "DQT", "`": "BQT",
}
_PLAIN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_BARE = re.compile(r"^[A-Za-z](?:[A-Za-z0-9_%]|\.(?=[A-Za-z0-9_%]))*$")


def _is_bare(name: str) -> bool:
    """Can ``name`` be written without quotes in FRETish (grammar rule NAME: a letter, then
    letters, digits, ``_``, ``%`` and inner ``.``; never a reserved word, nor one of the
    names FRET refuses bare, :data:`fretc.fretish.words.FRET_RESERVED`)?"""
    return (bool(_BARE.match(name)) and name.lower() not in RESERVED_WORDS
            and name not in RESERVED_LETTERS and name not in FRET_RESERVED)


def _mangle_char(ch: str) -> str:
    if ch.isascii() and ch.isalnum() or ch == "_":
        return ch
    code = FRET_CHAR_NAMES.get(ch)
    return f"_{code}_" if code else f"_U{ord(ch):04X}_"


@functools.lru_cache(maxsize=4096)
def mangle(name: str) -> str:
    """FRET's name for a FRETish identifier in printed formulas (FRET's name mangling,
    ../shared/fretish/README.md section 6b): in a bare name ``.`` -> ``_DOT_`` and ``%`` ->
    ``_PRC_`` (``ROS.ok`` -> ``ROS_DOT_ok``); a name that must be quoted in FRETish is
    mapped character by character with its quotes (``"weird var"`` ->
    ``_DQT_weird_SPC_var_DQT_``) using :data:`FRET_CHAR_NAMES`. Letters, digits and ``_``
    are kept. Characters FRET has no name for (non-ASCII) become ``_Uxxxx_`` (their code
    point): FRET would keep them, which no downstream tool accepts.

    The AST keeps names without their quotes, so a quoted name that could have been
    written bare (``"speed"``) is the same variable as the bare one and prints bare
    (FRET would print ``_DQT_speed_DQT_``, a second variable); likewise a quoted name of
    letters, digits and ``_`` that starts with ``_`` prints as is, which keeps the
    mangling idempotent (``mangle(mangle(x)) == mangle(x)``)."""
    if _PLAIN.match(name) and _is_bare(name if name[0] != "_" else "x" + name):
        return name  # also keeps mangle(mangle(x)) == mangle(x)
    if _is_bare(name):
        return "".join(_mangle_char(ch) for ch in name)
    return "_DQT_" + "".join(_mangle_char(ch) for ch in name) + "_DQT_"


_SMV_WORD = {"true": "TRUE", "false": "FALSE", "LAST": "LAST"}
#: Where a node keeps its printed text, by the spelling of the first-timepoint atom
_MEMO = {"FTP": "text", "(Z FALSE)": "ztext"}


def to_smv(node: Node, ftp: str = "FTP") -> str:
    """FRET/SMV text of ``node``. ``ftp`` is how the first-timepoint atom prints: FRET writes
    ``FTP`` in ft formulas and ``(Z FALSE)`` in pt formulas (pass ``"(Z FALSE)"``)."""
    if ftp not in _MEMO:
        raise ValueError("ftp must be 'FTP' or '(Z FALSE)'")
    return _smv(node, ftp, _MEMO[ftp])


def _smv(n: Node, ftp: str, memo: str) -> str:
    """The text of ``n``, kept on the node (attribute ``memo``): IR trees share sub-trees."""
    s = getattr(n, memo)
    if s is None:
        s = _smv_text(n, ftp, memo)
        setattr(n, memo, s)
    return s


def _smv_text(n: Node, ftp: str, memo: str) -> str:
    op, args = n.op, n.args

    def sub(i: int) -> str:
        return _smv(args[i], ftp, memo)

    if op in _SMV_WORD:
        return _SMV_WORD[op]
    if op == "FTP":
        return ftp
    if op in ("ap", "var"):
        return mangle(n.name)
    if op == "num":
        return name_of(n)
    if op == "!":
        return f"(! {sub(0)})"
    if op in ("cmp", "arith"):
        return f"({sub(0)} {n.name} {sub(1)})"
    if op == "neg":
        return f"(- {sub(0)})"
    if op in ("call", "fn", "pre"):
        return f"{mangle(n.name)}({','.join(_smv(a, ftp, memo) for a in args)})"
    if op == "ite":
        return f"ite({','.join(_smv(a, ftp, memo) for a in args)})"
    if op in ("past", "future"):  # a derived atom: its name, or its formula
        return n.name if n.name else sub(0)
    if op == "stream":  # (a FRET stream by its state bit: its name)
        return mangle(n.name)
    if len(args) == 2:
        return f"({sub(0)} {op} {sub(1)})"
    if n.hi is None:
        return f"({op} {sub(0)})"
    return f"({op}[{n.lo},{n.hi}] {sub(0)})"


_SPOT_OP = {"&": "&", "|": "|", "xor": "xor", "->": "->", "<->": "<->", "U": "U", "V": "R"}
_SPOT_KEYWORDS = {"true", "false", "xor", "and", "or", "not", "implies", "equiv", "t", "f"}
_SPOT_BARE = re.compile(r"^[a-z_][a-z0-9_]*$")


@functools.lru_cache(maxsize=4096)
def spot_ap(text: str) -> str:
    """An atomic proposition in Spot syntax: bare when it is a lower-case identifier Spot
    cannot mistake for an operator, otherwise double-quoted (``"x > 3"``)."""
    if _SPOT_BARE.match(text) and text not in _SPOT_KEYWORDS:
        return text
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def to_spot(node: Node) -> str:
    """Spot LTL text of a future-time formula. Raises ``ValueError`` on past operators."""
    return _spot(node)


def _spot(n: Node) -> str:
    s = n.stext
    if s is not None:
        return s
    op = n.op
    if op in _SPOT_OP:
        s = f"({_spot(n.args[0])} {_SPOT_OP[op]} {_spot(n.args[1])})"
    elif op == "!":
        s = f"!{_spot(n.args[0])}"
    elif op == "ap":
        s = spot_ap(mangle(n.name))
    elif op in ("X", "F", "G"):
        s = (f"({op} {_spot(n.args[0])})" if n.hi is None else
             f"({op}[{n.lo}..{n.hi}] {_spot(n.args[0])})")
    elif op == "true":
        s = "true"
    elif op == "false":
        s = "false"
    elif op in ("LAST", "FTP", "cmp", "call", "past", "future"):
        s = spot_ap(to_smv(n))
    elif op in ("Y", "Z", "O", "H", "S", "T"):
        raise ValueError("Spot has no past-time operators: a pt formula cannot be printed "
                         "in Spot syntax")
    else:
        raise ValueError(f"no Spot form for IR node {op!r}")
    n.stext = s
    return s


def expr_text(e: A.Expr) -> str:
    """FRET's printed form of an AST expression: binary operations parenthesized, calls as
    ``f(a,b)``, identifiers mangled."""
    if isinstance(e, A.Var):
        return mangle(e.name)
    if isinstance(e, A.BoolLit):
        return "TRUE" if e.value else "FALSE"
    if isinstance(e, A.NumLit):
        return e.text
    if isinstance(e, A.Unary):
        return f"(! {expr_text(e.operand)})" if e.op == "!" else f"(- {expr_text(e.operand)})"
    if isinstance(e, A.Binary):
        return f"({expr_text(e.left)} {e.op} {expr_text(e.right)})"
    if isinstance(e, A.Call) and e.name == SINCE and len(e.args) == 2:
        return f"({expr_text(e.args[0])} S {expr_text(e.args[1])})"  # (FRET's pt since)
    if isinstance(e, A.Call) and stream_name(e) is not None:  # (a stream by its state bit)
        return mangle(str(stream_name(e)))
    if isinstance(e, A.Call):
        return f"{mangle(e.name)}({','.join(expr_text(a) for a in e.args)})"
    raise TypeError(type(e))
