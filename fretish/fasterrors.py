"""Syntax errors without Lark: Lark's own failure on a sentence, found by replaying Lark's
algorithm on the fast path's tables (:mod:`fretish.fastparse`).

A sentence the fast path cannot parse used to go to Lark for its exact error: importing
Lark, loading its tables and building the contextual lexer's scanners for every parser state
the sentence passes through cost 0.15-0.2 s of CPU for one bad
sentence, paid by a user at every typo. The error only depends on what Lark does
with the text, and what Lark does is fixed by its tables (the fast path's copy of them) and
its documented algorithm (Lark 1.x, ``lark/lexer.py`` and ``lark/parsers/``), replayed
here step for step:

* the **contextual lexer**: in parser state ``S`` the terminals tried at a position are
  those ``S`` has an action for, plus the ignored ones, in Lark's order (priority, then
  longest possible match, ...); the first whose regexp matches there wins (Lark joins them
  into one alternation, which is the same: an alternation takes its first alternative that
  matches). When none matches, Lark tries every terminal (its "root lexer"): a match is an
  unexpected token whose expected set is ``S``'s terminals, no match an unexpected
  character with that set;
* the **LALR(1) parser**: reductions call the AST builder's callbacks as Lark does (the
  fast path's wrapped callbacks, :class:`fretish.fastparse._FastParser`), so a rule FRETish
  forbids (``_Fail``) is found in the same order; a token with no action in the state
  reached is an unexpected token whose expected set is that state's terminals; at the end
  ``$END`` is fed the same way;
* :func:`fretish.diagnostics.accepted_before`: the terminals the parser accepts in the state
  before the offending token (Lark's ``InteractiveParser.accepts``: each terminal of the
  state fed to a copy of the stacks, without callbacks).

The result goes through the very functions that turn Lark's exception into the message
(:func:`fretish.diagnostics.explain_failure`), so the error is byte for byte Lark's.
Anything this module does not reproduce - a builder callback that raises, a shift on
``$END``, an exception of its own - returns None and the caller asks Lark, which stays the
reference: ``tests/fretish/test_fasterrors.py`` compares the two on many bad sentences
(hypothesis mutations of good ones, the case-study corpus and the error tests' sentences).
"""

from __future__ import annotations

import re

__all__ = ["lark_failure"]

#: compiled regexp of each terminal, by (regexp, flags) (re's own cache is bounded)
_COMPILED: dict = {}


class _Gives(Exception):
    """Internal: the replay does not reproduce Lark here (the caller asks Lark)."""


def _match(rx: str, flags: int, text: str, pos: int):
    m = _COMPILED.get((rx, flags))
    if m is None:
        compiled = re.compile(rx, flags)
        if compiled.groups:  # a group of its own would change Lark's m.lastgroup
            raise _Gives("terminal with a group")
        m = _COMPILED[(rx, flags)] = compiled.match
    return m(text, pos)


def _first_match(fast, text: str, pos: int, allowed) -> tuple | None:
    """``(terminal, end)`` of the first terminal (Lark's order) of ``allowed`` (names; None:
    every terminal) whose regexp matches ``text`` at ``pos``; None when none does. Only the
    terminals that can start with ``text[pos]`` are tried (the fast path's dispatch, a
    superset of those that match)."""
    ch = text[pos]
    subsets = fast.subsets
    candidates = subsets[fast.dispatch.get(ch, len(subsets) - 1)]
    terminals, flags = fast.terminals, fast.flags
    for i in candidates:
        name, rx = terminals[i]
        if allowed is not None and name not in allowed:
            continue
        m = _match(rx, flags, text, pos)
        if m is not None:
            return name, m.end()
    return None


def _terminals_of(fast, state: int, names: set) -> set:
    """The terminal names (of ``names``, all the terminals) of parser state ``state``: its
    lexer's terminals (Lark's ``ContextualLexer`` keeps the state's keys that are
    terminals; ``$END`` is none)."""
    return {t for t in fast.actions[state] if t in names}


def _reduce_or_shift(fast, state_stack: list, value_stack: list | None, typ: str, tok,
                     end_state: int | None) -> str:
    """Feed terminal ``typ`` (value ``tok``) as Lark's ``ParserState.feed_token`` does:
    ``"shift"``, ``"end"`` (``$END`` reduced to ``end_state``) or ``"error"`` (no action:
    the stacks are left in the state that has none). ``value_stack`` None: no callbacks
    (``accepts``)."""
    actions, gotos, rules, unit = fast.actions, fast.gotos, fast.rules, fast.unit
    while True:
        state = state_stack[-1]
        action = actions[state].get(typ)
        if action is None:
            return "error"
        if action >= 0:
            if end_state is not None:
                raise _Gives("a shift on $END")  # Lark's parser asserts there is none
            state_stack.append(action)
            if value_stack is not None:
                value_stack.append(tok)
            return "shift"
        origin, size, callback, up = rules[~action]
        if value_stack is not None and not unit[~action]:
            # as fastparse._FastParser.parse: a unit rule passes its child up unchanged
            if up:
                value = value_stack[up]
            elif size:
                value = callback(value_stack[-size:])
            else:
                value = callback([])
            if size:
                del value_stack[-size:]
            value_stack.append(value)
        if size:
            del state_stack[-size:]
        state_stack.append(gotos[state_stack[-1]][origin])
        if end_state is not None and state_stack[-1] == end_state:
            return "end"


def _accepts(fast, stack: list, start: str) -> set:
    """Lark's ``InteractiveParser.accepts()`` on the state stack ``stack``: the terminals
    of the top state (its keys in upper case, ``$END`` included) that a copy of the stacks
    takes without error."""
    out = set()
    end_state = fast.end_states[start]
    for t in fast.actions[stack[-1]]:
        if not t.isupper():
            continue
        is_end = t == "$END"
        got = _reduce_or_shift(fast, list(stack), None, t, None,
                               end_state if is_end else None)
        if got != "error":
            out.add(t)
    return out


def lark_failure(fast, text: str, start: str, own=()) -> tuple | None:
    """How Lark fails on ``text`` from start symbol ``start``, replayed on the fast path's
    tables (module docstring): ``(pos, value, terminal, expected)`` as
    :func:`fretish.diagnostics.translate` reads Lark's exception (``value`` None at the end
    of the text), with ``expected`` already replaced by the replayed set of
    :func:`~fretish.diagnostics.accepted_before` when that set is not empty. None when the
    replay cannot say (Lark decides): the text parses, a builder callback raises, or a case
    not reproduced. An exception of the classes ``own`` raised by a builder callback is
    raised as is: Lark raises it too, at the same reduction (the same callbacks run in the
    same order on the same tokens). The caller sets the builder's context
    (``fretish.parser._ctx``)."""
    try:
        return _replay(fast, text, start)
    except own:
        raise
    except Exception:  # noqa: BLE001 - anything unforeseen: Lark, the reference, decides
        return None


def _replay(fast, text: str, start: str):
    ignore = fast.ignore
    end_state = fast.end_states[start]
    state_stack = [fast.start_states[start]]
    value_stack: list = []
    pos, n = 0, len(text)
    names = {name for name, _ in fast.terminals}
    while True:
        # the contextual lexer: the next token in the state on top of the stack
        state = state_stack[-1]
        allowed = _terminals_of(fast, state, names)
        tok = None
        while pos < n:
            found = _first_match(fast, text, pos, allowed | ignore)
            if found is None:
                break
            typ, end = found
            if typ in ignore:
                pos = end
                continue
            tok = (typ, text[pos:end], pos, end)
            break
        if tok is None and pos < n:
            before = list(state_stack)
            root = _first_match(fast, text, pos, None)
            expected = allowed - ignore or {"<END-OF-FILE>"}
            if root is None:  # UnexpectedCharacters(allowed)
                from .diagnostics import _WORD  # the offending word, as _locate takes it

                m = _WORD.match(text, pos)
                return _result(fast, text, start, before, pos,
                               m.group(0) if m else text[pos], "CHAR", expected)
            typ, end = root   # the root lexer's token: UnexpectedToken(token, allowed)
            if typ in ignore:
                raise _Gives("ignored terminal from the root lexer")
            return _result(fast, text, start, before, pos, text[pos:end], typ, expected)
        if tok is None:  # the end of the text: $END
            before = list(state_stack)
            got = _reduce_or_shift(fast, state_stack, value_stack, "$END", None, end_state)
            if got == "end":
                return None  # it parses: not a syntax error
            return _result(fast, text, start, before, n, None, "$END",
                           _upper_keys(fast, state_stack[-1]))
        before = list(state_stack)
        got = _reduce_or_shift(fast, state_stack, value_stack, tok[0], tok, None)
        if got == "error":
            return _result(fast, text, start, before, tok[2], tok[1], tok[0],
                           _upper_keys(fast, state_stack[-1]))
        pos = tok[3]


def _upper_keys(fast, state: int) -> set:
    """Lark's expected set of an ``UnexpectedToken`` raised by the parser: the state's keys
    in upper case (terminals and ``$END``; nonterminals are lower case)."""
    keys = set(fast.actions[state]) | set(fast.gotos[state])
    return {k for k in keys if k.isupper()}




def _result(fast, text, start, before, pos, value, typ, expected):
    """As :func:`fretish.diagnostics.translate` after :func:`_locate`: the position (the
    end of the stripped text for ``$END``) and the replayed accepted set (the stack
    ``before`` the offending token) in place of ``expected`` when not empty."""
    replayed = _accepts(fast, before, start)
    if value is None:
        pos = len(text.rstrip())
    return pos, value, typ, (replayed or set(expected))
