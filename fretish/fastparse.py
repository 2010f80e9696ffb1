"""The parser's fast path: Lark's LALR(1) table for ``grammar.lark`` run by a plain loop
(:class:`_FastParser`), with a whole-text lexer, calling the AST builder of
:mod:`fretish.parser` on each reduction as Lark would.

:func:`fast_tables` takes what the loop needs from a Lark parser, as plain data (cached by
:mod:`fretish.parser`, so a run on valid sentences does not import Lark). A text the fast
path cannot parse raises :class:`_Slow` (or the builder's error), and the caller parses it
again with Lark, the reference, which reports the exact error;
``tests/fretish/test_fast_parser.py`` compares the two on every test sentence.
"""

from __future__ import annotations

import re

from .words import RESERVED_LETTERS, RESERVED_WORDS

__all__ = ["fast_tables"]


class _Slow(Exception):
    """The fast path cannot decide this text: parse it with Lark (errors included)."""


class _Inline:
    """The children of an inlined rule (``_name``, Lark's anonymous ``__x_star`` rules),
    spliced into the parent's children as Lark's child filter does with its trees."""
    __slots__ = ("children",)

    def __init__(self, children):
        self.children = children


def fast_tables(lark, builder) -> dict | None:
    """What :class:`_FastParser` needs from a Lark parser of ``grammar.lark``, as plain data
    (marshalled in fretc's cache beside Lark's own entry, so a run loads it without importing
    Lark): the terminals in the order Lark's lexer tries them, Lark's LALR table, and per
    rule its origin, length, callback name and Lark's child filter (``_``-prefixed
    terminals dropped, ``_``-prefixed rules spliced, ``?rule`` single children passed up).
    Per terminal, the characters it can start with and whether it matches the same way
    whatever surrounds it (for the lexer, :meth:`_FastParser._build_scanner`).
    None when the grammar uses a Lark feature the fast path does not reproduce (a terminal
    callback or a string terminal that a regexp terminal also matches)."""
    from lark.lexer import _create_unless, _regexp_has_newline
    from lark.parsers.lalr_analysis import Shift

    conf = lark.lexer_conf
    terminals = list(conf.terminals)
    terminal_names = {t.name for t in terminals} | {"$END"}
    terminals.sort(key=lambda x: (-x.priority, -x.pattern.max_width, -len(x.pattern.value),
                                  x.name))
    kept, callbacks = _create_unless(terminals, conf.g_regex_flags, conf.re_module,
                                     conf.use_bytes)
    if callbacks or conf.callbacks or len(kept) != len(terminals) or conf.use_bytes \
            or any(hasattr(builder, t.name) for t in terminals) or lark.options.postlex:
        return None
    parser = lark.parser.parser.parser
    table = parser.parse_table
    index = {}
    rules = []
    for rule in lark.rules:
        exp = rule.expansion
        opts = rule.options
        include = [(i, not sym.is_term and sym.name.startswith("_"))
                   for i, sym in enumerate(exp)
                   if opts.keep_all_tokens or not (sym.is_term and sym.filter_out)]
        filtered = len(include) < len(exp) or any(x for _, x in include)
        index[rule] = len(rules)
        rules.append((str(rule.origin.name), len(exp),
                      str(rule.alias or opts.template_source or rule.origin.name),
                      bool(opts.expand1 and not rule.alias),
                      tuple(include) if filtered else None))
    n_states = max(table.states) + 1
    actions: list = [{} for _ in range(n_states)]
    gotos: list = [{} for _ in range(n_states)]
    for s, acts in table.states.items():
        for t, (act, arg) in acts.items():
            if act is not Shift:
                actions[s][str(t)] = ~index[arg]
            elif t in terminal_names:
                actions[s][str(t)] = int(arg)
            else:
                gotos[s][str(t)] = int(arg)
    firsts = [_first_chars(t.pattern.to_regexp(), conf.g_regex_flags) for t in terminals]
    # the terminal of each reserved word as written in any of the usual letter cases, by
    # the exact lexer (all terminals in Lark's order), for _FastParser._word_type
    exact = re.compile("|".join(f"(?P<{t.name}>{t.pattern.to_regexp()})" for t in terminals),
                       conf.g_regex_flags).match
    words = {}
    for w in sorted(RESERVED_WORDS | RESERVED_LETTERS | {"what"}):
        for v in (w, w.lower(), w.upper(), w.capitalize()):
            m = exact(v)
            if m is not None and m.end() == len(v):
                words[v] = str(m.lastgroup)
    subsets: dict = {}
    dispatch = {}
    for ch in _ASCII:
        subset = tuple(i for i, f in enumerate(firsts) if f is None or ch in f)
        dispatch[ch] = subsets.setdefault(subset, len(subsets))
    return {"terminals": [(str(t.name), str(t.pattern.to_regexp())) for t in terminals],
            "dispatch": dispatch, "subsets": list(subsets),
            "flags": int(conf.g_regex_flags), "ignore": sorted(str(t) for t in conf.ignore),
            "newline": sorted(str(t.name) for t in terminals
                              if _regexp_has_newline(t.pattern.to_regexp())),
            "words": words, "firsts": [None if f is None else "".join(sorted(f)) for f in firsts],
            "context_free": [_context_free(t.pattern.to_regexp(), conf.g_regex_flags)
                             for t in terminals],
            "actions": actions, "gotos": gotos, "rules": rules,
            "start_states": {str(k): int(v) for k, v in table.start_states.items()},
            "end_states": {str(k): int(v) for k, v in table.end_states.items()}}


_ASCII = [chr(i) for i in range(128)]


def _first_chars(rx: str, flags: int) -> frozenset | None:
    """A superset of the ASCII characters a match of regexp ``rx`` can start with (None: it
    may start with any), from the parse tree of Python's ``re``: zero-width assertions are
    skipped (so the set only grows), anything not understood means "any"."""
    import re._constants as C
    import re._parser as P

    def chars(codes, icase):
        out = set()
        for code in codes:
            ch = chr(code)
            out.update(x for x in _ASCII
                       if x == ch or (icase and re.fullmatch(re.escape(ch), x, re.I)))
        return out

    def first(seq, icase):            # -> (set or None, nullable)
        out: set = set()
        for op, av in seq:
            if op in (C.ASSERT, C.ASSERT_NOT, C.AT):
                continue
            if op is C.LITERAL:
                return out | chars([av], icase), False
            if op is C.IN:
                codes = []
                for iop, iav in av:
                    if iop is C.LITERAL:
                        codes.append(iav)
                    elif iop is C.RANGE:
                        codes.extend(range(iav[0], iav[1] + 1))
                    else:
                        return None, False
                return out | chars(codes, icase), False
            if op is C.SUBPATTERN:
                _, add, dele, sub = av
                sub_icase = (icase or bool(add & re.I)) and not dele & re.I
                got, nullable = first(sub, sub_icase)
            elif op is C.BRANCH:
                got, nullable = set(), False
                for alt in av[1]:
                    g, nl = first(alt, icase)
                    if g is None:
                        return None, False
                    got |= g
                    nullable = nullable or nl
            elif op in (C.MAX_REPEAT, C.MIN_REPEAT, C.POSSESSIVE_REPEAT):
                lo, _, sub = av
                got, nullable = first(sub, icase)
                nullable = nullable or lo == 0
            else:
                return None, False
            if got is None:
                return None, False
            out |= got
            if not nullable:
                return out, False
        return out, True

    tree = P.parse(rx, flags)
    got, nullable = first(tree.data, bool(tree.state.flags & re.I))
    return None if got is None or nullable else frozenset(got)


def _context_free(rx: str, flags: int) -> bool:
    """Whether regexp ``rx`` matches a text the same way whatever follows or precedes it:
    no lookaround, anchor or back-reference (from the parse tree of Python's ``re``)."""
    import re._constants as C
    import re._parser as P

    def plain(seq) -> bool:
        for op, av in seq:
            if op in (C.ASSERT, C.ASSERT_NOT, C.AT, C.GROUPREF, C.GROUPREF_EXISTS):
                return False
            if op is C.SUBPATTERN and not plain(av[-1]):
                return False
            if op is C.BRANCH and not all(plain(alt) for alt in av[1]):
                return False
            if op in (C.MAX_REPEAT, C.MIN_REPEAT, C.POSSESSIVE_REPEAT) and not plain(av[2]):
                return False
            if op is C.ATOMIC_GROUP and not plain(av):
                return False
        return True

    return plain(P.parse(rx, flags).data)


def _alphabet(rx: str, flags: int) -> frozenset | None:
    """A superset of the characters a match of regexp ``rx`` can consume or look at
    (lookarounds included), when they are all ASCII and known; None otherwise (a negated
    class, ``.``, a category such as ``\\s``, a letter matched in any case, an anchor, a
    back-reference: anything not understood). From the parse tree of Python's ``re``, like :func:`_first_chars`."""
    import re._constants as C
    import re._parser as P

    out: set = set()

    def add(code: int, icase: bool) -> bool:
        ch = chr(code)
        if code >= 128 or (icase and ch.isalpha()):   # (a letter's other cases: not only
            return False                              # ASCII ones, e.g. the Kelvin sign)
        out.add(ch)
        return True

    def walk(seq, icase) -> bool:
        for op, av in seq:
            if op is C.LITERAL:
                if not add(av, icase):
                    return False
            elif op is C.IN:
                for iop, iav in av:
                    if iop is C.LITERAL:
                        if not add(iav, icase):
                            return False
                    elif iop is C.RANGE:
                        if iav[1] >= 128:
                            return False
                        for code in range(iav[0], iav[1] + 1):
                            add(code, icase)
                    else:
                        return False
            elif op is C.SUBPATTERN:
                _, add_flags, del_flags, sub = av
                if not walk(sub, (icase or bool(add_flags & re.I)) and not del_flags & re.I):
                    return False
            elif op is C.BRANCH:
                if not all(walk(alt, icase) for alt in av[1]):
                    return False
            elif op in (C.MAX_REPEAT, C.MIN_REPEAT, C.POSSESSIVE_REPEAT):
                if not walk(av[2], icase):
                    return False
            elif op in (C.ASSERT, C.ASSERT_NOT):
                if not walk(av[1], icase):
                    return False
            elif op is C.ATOMIC_GROUP:
                if not walk(av, icase):
                    return False
            else:
                return False
        return True

    tree = P.parse(rx, flags)
    return frozenset(out) if walk(tree.data, bool(tree.state.flags & re.I)) else None


def _class_escape(ch: str) -> str:
    """``ch`` written inside a regexp character class."""
    return "\\" + ch if ch in "\\]^-[" else ch if ch.isprintable() else f"\\x{ord(ch):02x}"


class _FastParser:
    """Lark's LALR(1) table for ``grammar.lark`` run by a plain loop, with one lexer regexp.

    The grammar's terminals never overlap (its header: a keyword matches only its word and
    NAME refuses every reserved word), so the one regexp of all terminals, tried in the
    order Lark's lexer tries them, gives the token the contextual lexer would give in every
    state where that token can be shifted: the first alternative that matches is the same
    in the state's subset and in the whole set whenever it belongs to the subset. The text
    is cut into tokens by one ``findall`` (:meth:`_build_scanner`), or, when it has no
    blank but spaces and no quote, chunk by chunk at its spaces, each distinct chunk text
    cut by that ``findall`` once (:meth:`_build_chunk_lexer`); a token's terminal is
    that regexp's on the token alone, split by the token's first character (only the
    terminals that can start with it, :func:`_first_chars`, a superset, in the same order,
    so the first match is the same; each part compiled on first use) and kept by text.

    Tokens are tuples ``(terminal, text, start, end)`` (0-based offsets). Each is fed to
    Lark's table and each reduction calls the builder's callback for the rule (the
    :class:`fretish.parser._Builder` given), wrapped as Lark wraps it (:func:`fast_tables`),
    so a sentence parsed here gets the AST Lark gives (a run of one-symbol reductions is
    one lookup, :meth:`_plan`). Anything else - a character no
    terminal matches, a token the state does not accept, an error raised by the builder -
    raises :class:`_Slow`, and the sentence is parsed again by Lark for its exact error
    (tests/fretish/test_fast_parser.py compares the two on every test sentence)."""

    def __init__(self, tables: dict, builder):
        self.terminals = tables["terminals"]
        self.flags = tables["flags"]
        self.subsets = tables["subsets"] + [tuple(range(len(self.terminals)))]
        self.dispatch = tables["dispatch"]       # ASCII character -> index into subsets
        self.matchers = [None] * len(self.subsets)  # compiled on first use
        self.parts: dict = {}                     # terminal indices -> compiled match
        self.ignore = frozenset(tables["ignore"])
        self.actions = tables["actions"]
        self.gotos = tables["gotos"]
        self.start_states = tables["start_states"]
        self.end_states = tables["end_states"]
        self.rules = [(origin, size, self._callback(builder, origin, name, expand1, include),
                       self._passed_up(size, expand1, include))
                      for origin, size, name, expand1, include in tables["rules"]]
        self.known_words = tables["words"]
        # rules that reduce one symbol to itself (a ``?rule`` passing its single child up):
        # reducing by one leaves the value stack as it is and replaces only the top state
        self.unit = [size == 1 and up == -1 for _, size, _, up in self.rules]
        # rules of one symbol (unit or not): reducing by one replaces only the top of both
        # stacks, so the state below stays and a run of them is a function of the states
        self.single = [size == 1 for _, size, _, _ in self.rules]
        #: (state below, top state, terminal) -> :meth:`_plan` of that run of one-symbol
        #: reductions
        self.plans: dict = {}
        self._build_scanner([None if f is None else frozenset(f) for f in tables["firsts"]],
                            tables["context_free"])

    @staticmethod
    def _passed_up(size, expand1, include) -> int:
        """For a ``?rule`` whose filtered children are always exactly one child (no splice),
        that child's index counted from the end of the rule (Lark's callback returns it
        as is); 0 otherwise."""
        kept = [(i, splice) for i, splice in include] if include is not None else \
            [(i, False) for i in range(size)]
        if expand1 and len(kept) == 1 and not kept[0][1]:
            return kept[0][0] - size
        return 0

    def _matcher(self, sid: int):
        """The ``match`` of subset ``sid``: its terminals tried in Lark's order. A long
        regexp (NAME's, with its reserved-word lookahead) is a part of its own, compiled
        once and shared by every subset (trying the parts in turn is the alternation of
        them all: the first alternative that matches wins either way)."""
        subset = self.subsets[sid]
        if not subset:
            raise _Slow("no terminal starts with this character")
        parts, run = [], []
        for i in subset:
            if len(self.terminals[i][1]) > 200:
                if run:
                    parts.append(tuple(run))
                    run = []
                parts.append((i,))
            else:
                run.append(i)
        if run:
            parts.append(tuple(run))
        matches = [self._part(p) for p in parts]
        if len(matches) == 1:
            m = matches[0]
        else:
            def m(text, pos, matches=matches):
                for match in matches:
                    found = match(text, pos)
                    if found is not None:
                        return found
                return None
        self.matchers[sid] = m
        return m

    def _part(self, indices: tuple):
        got = self.parts.get(indices)
        if got is None:
            got = self.parts[indices] = re.compile(
                "|".join(f"(?P<{self.terminals[i][0]}>{self.terminals[i][1]})"
                         for i in indices), self.flags).match
        return got

    @staticmethod
    def _callback(builder, origin, name, expand1, include):
        f = getattr(builder, name, None)
        if f is None:
            if not origin.startswith("_"):
                def f(children):  # Lark would build a Tree: not a FRETish AST
                    raise _Slow(origin)
            else:
                f = _Inline
        if expand1:
            inner = f

            def f(children, inner=inner):
                return children[0] if len(children) == 1 else inner(children)
        if include is not None and not any(splice for _, splice in include):
            inner2 = f
            kept = tuple(i for i, _ in include)

            def f(children, inner=inner2, kept=kept):
                return inner([children[i] for i in kept])
        elif include is not None:
            inner2 = f

            def f(children, inner=inner2, include=include):
                out = []
                for i, splice in include:
                    if splice:
                        if out:
                            out += children[i].children
                        else:
                            out = children[i].children
                    else:
                        out.append(children[i])
                return inner(out)
        return f

    # ---- the lexer: one regexp over the whole text
    #: An identifier-shaped word: a letter, then letters, digits, ``_``, ``%`` and inner
    #: ``.`` (NAME's run, ``[A-Za-z](?:[A-Za-z0-9_%]|\.(?=[A-Za-z0-9_%]))*``, written so
    #: that Python's re repeats single classes: the same words, tested)
    _WORD = r"[A-Za-z][A-Za-z0-9_%]*(?:\.[A-Za-z0-9_%]+)*"
    _LETTERS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz")
    _MAX_WORDS = 100_000

    def _build_scanner(self, firsts: list, context_free: list) -> None:
        """The whole-text lexer, when the grammar's terminals allow it (else the lexer of
        :meth:`_tokens_by_char` is used): one regexp ``((ignored)*)(word | T1 | T2 ... |
        \\Z)`` run by ``findall``, where ``word`` is an identifier-shaped run of characters
        (FRETish's keywords, reserved letters and names all are: each keyword terminal ends
        where the word ends, and NAME's regexp is the same run) and ``T1, T2 ...`` are the
        other terminals in Lark's order. ``findall`` gives (ignored text, token text) pairs,
        so the offsets are the running sum of their lengths; a character no terminal
        matches is skipped by ``findall``, which the sum then shows (the last pair is the
        ``\\Z`` one, ending at the text's end when nothing was skipped).

        A token's terminal is that of the exact lexer (:meth:`_matcher`) on the token's
        text alone, kept in :attr:`words` by text: for a word, it never depends on what
        follows a whole word; for the other terminals, whose regexps are required to have
        no lookaround, anchor or back-reference, a terminal that matches the text alone
        matches it in place too, so the first one in Lark's order is the same. Used only
        when every terminal starts either with letters only or with no letter, and the
        ignored terminals start with characters no other terminal starts with. ``firsts``
        and ``context_free`` are per terminal (:func:`fast_tables`: :func:`_first_chars`,
        :func:`_context_free`)."""
        self.findall = None
        self.chunk_stop = None
        letters = self._LETTERS
        ignored, others = [], []
        ignore_firsts: set = set()
        for i, (name, rx) in enumerate(self.terminals):
            f = firsts[i]
            if f is None:
                return
            if name in self.ignore:
                ignored.append(rx)
                ignore_firsts |= f
            elif not f & letters:
                if not context_free[i]:
                    return
                others.append(i)
            elif not f <= letters:
                return
        if not ignored or any(f is None or (f & ignore_firsts)
                              for i, f in enumerate(firsts)
                              if self.terminals[i][0] not in self.ignore):
            return
        body = "".join(f"|(?:{self.terminals[i][1]})" for i in others)
        # a run of ignored text; one character class repeated (FRETish's blanks) is written
        # as one repeat of the class, which Python's re runs much faster than a repeat of a
        # repeat (the same runs match)
        run = f"(?:{'|'.join(ignored)})*"
        if len(ignored) == 1 and re.fullmatch(r"\[[^\]\[]*\]\+", ignored[0]):
            run = ignored[0][:-1] + "*"
        rx = re.compile(f"({run})((?:{self._WORD}){body}|\\Z)", self.flags)
        if rx.groups != 2:   # a terminal with a capturing group of its own
            return
        self.findall = rx.findall
        self._build_chunk_lexer(ignored, [self._WORD] + [self.terminals[i][1] for i in others],
                                [self._LETTERS] + [firsts[i] for i in others])
        self.words = dict(self.known_words)
        names = [i for i, (name, _) in enumerate(self.terminals) if name == "NAME"]
        # NAME tried first among the terminals that start with a letter: a word it matches
        # whole is a NAME (else the exact lexer decides)
        self.name_first = bool(names) and all(f is not None and not f & letters
                                              for f in firsts[:names[0]])
        self.name_rx = self.terminals[names[0]][1] if names else None
        self.name_match = None

    def _build_chunk_lexer(self, ignored: list, alternatives: list, firsts: list) -> None:
        """The lexer by space-separated chunks (:meth:`_tokens_by_chunk`), when it gives the
        whole-text lexer's tokens: a run of spaces is ignored text, and only a token that
        starts with one of :attr:`chunk_stop`'s characters can hold a space (FRETish: a
        quoted string).

        :attr:`chunk_stop` is then the ``search`` of a regexp of the characters that send
        a text to the whole-text lexer: the ignored characters other than the space, and
        those starting a token that may hold a space. In a text without them, the ignored
        text is runs of spaces, so ``str.split(" ")`` cuts it into chunks each of which is
        whole tokens (or empty, between two spaces); and since no ``alternatives`` regexp
        (``findall``'s token part) can match a space or look at one (:func:`_alphabet`),
        each chunk alone is cut as the whole text cuts it there."""
        self.chunks: dict = {}
        self.chunk_stop = None
        kept: frozenset = frozenset()
        for rx in ignored:
            alpha = _alphabet(rx, self.flags)
            if alpha is None:
                return
            kept |= alpha
        if not any(re.fullmatch(rx, " ", self.flags) for rx in ignored):
            return
        stop = set(kept - {" "})
        for rx, first in zip(alternatives, firsts):
            alpha = _alphabet(rx, self.flags)
            if alpha is None or " " in alpha:
                if first is None:
                    return
                stop |= first
        self.chunk_stop = re.compile("[" + "".join(sorted(map(_class_escape, stop))) + "]"
                                     if stop else "(?!)").search

    def _tokens_by_chunk(self, text: str) -> list:
        """The tokens of ``text`` (as :meth:`_tokens`), for a text without the characters
        of :attr:`chunk_stop` (:meth:`_build_chunk_lexer`): the chunks of ``str.split(" ")``
        at offsets counted from their lengths, each chunk text cut into tokens once
        (:attr:`chunks`: the terminal of a one-token chunk, else its tokens with offsets
        from the chunk's start)."""
        chunks = self.chunks
        out = []
        add = out.append
        begin = 0
        for chunk in text.split(" "):
            if chunk:
                end = begin + len(chunk)
                lexed = chunks.get(chunk) or self._lex_chunk(chunk)
                if type(lexed) is str:
                    add((lexed, chunk, begin, end))
                else:
                    for typ, value, s, e in lexed:
                        add((typ, value, begin + s, begin + e))
                begin = end + 1
            else:
                begin += 1
        return out

    def _lex_chunk(self, chunk: str):
        """The tokens of one chunk (:meth:`_tokens_by_chunk`), by the whole-text lexer's
        regexp; :class:`_Slow` where a character starts no terminal."""
        words = self.words
        out = []
        pos = 0
        for _, value in self.findall(chunk):
            if not value:           # the \Z match
                break
            out.append((words.get(value) or self._word_type(value), value, pos,
                        pos + len(value)))
            pos += len(value)
        if pos != len(chunk) or not out:
            raise _Slow("no terminal")
        if len(self.chunks) >= self._MAX_WORDS:
            self.chunks.clear()
        lexed = self.chunks[chunk] = out[0][0] if len(out) == 1 else tuple(out)
        return lexed

    def _tokens(self, text: str) -> list:
        """The tokens of ``text`` (``(terminal, text, start, end)`` tuples, ignored
        terminals dropped) by the whole-text lexer (:meth:`_build_scanner`); raises
        :class:`_Slow` where a character starts no terminal."""
        findall = self.findall
        if findall is None:
            return self._tokens_by_char(text)
        words = self.words
        found = findall(text)
        # the \Z matches, last: the ignored characters at the end, then (after them)
        # an empty match at the very end
        end = 0
        while found and not found[-1][1]:
            end += len(found.pop()[0])
        out = []
        add = out.append
        pos = 0
        for ignored, value in found:
            start = pos + len(ignored)
            pos = start + len(value)
            add((words.get(value) or self._word_type(value), value, start, pos))
        if pos + end != len(text):
            raise _Slow("no terminal")
        return out

    def _word_type(self, word: str) -> str:
        """The terminal of token text ``word`` (:meth:`_build_scanner`): the exact lexer on
        the text alone (:class:`_Slow` when no terminal matches it whole), or NAME when
        NAME, the first terminal a word can start, matches it whole. The reserved words'
        terminals come with the tables (:attr:`known_words`), so a run compiles no keyword
        regexp."""
        if not word:
            raise _Slow("empty token")
        if len(self.words) >= self._MAX_WORDS:
            self.words = dict(self.known_words)
        if self.name_first and word[0] in self._LETTERS:
            if self.name_match is None:
                self.name_match = re.compile(self.name_rx, self.flags).match
            m = self.name_match(word)
            if m is not None and m.end() == len(word):
                self.words[word] = "NAME"
                return "NAME"
        sid = self.dispatch.get(word[0], len(self.subsets) - 1)
        m = (self.matchers[sid] or self._matcher(sid))(word, 0)
        if m is None or m.end() != len(word):
            raise _Slow("word")
        typ = self.words[word] = m.lastgroup
        return typ

    def _tokens_by_char(self, text: str) -> list:
        """The tokens of ``text`` (``(terminal, text, start, end)`` tuples, ignored
        terminals dropped) by the exact lexer, one regexp match per token or ignored run
        (used when the whole-text lexer of :meth:`parse` cannot be); raises :class:`_Slow`
        where a character starts no terminal."""
        ignore = self.ignore
        dispatch, matchers, full = self.dispatch, self.matchers, len(self.subsets) - 1
        out = []
        pos, n = 0, len(text)
        while pos < n:
            sid = dispatch.get(text[pos], full)
            match = matchers[sid] or self._matcher(sid)
            m = match(text, pos)
            if m is None:
                raise _Slow("no terminal")
            typ = m.lastgroup
            end = m.end()
            if typ not in ignore:
                out.append((typ, text[pos:end], pos, end))
            pos = end
        return out

    def _plan(self, key: tuple) -> tuple:
        """The run of one-symbol reductions (rules of size 1: a ``?rule`` passing its child
        up, or a rule whose callback turns its one child into a value) taken from top state
        ``key[1]``, with state ``key[0]`` below it, on lookahead ``key[2]``, and what follows
        it: ``(callbacks, state, action)``. ``callbacks`` are those of the run's non-unit
        rules in order (each applied to the top value, as ``[value]``), ``state`` the top
        state after the run, ``action`` the table's action there on the lookahead (a shift,
        a reduction by a rule of another size, or None for an error).

        A one-symbol reduction leaves the stacks' depth and the state below the top as they
        are, so the run is a function of the key alone (the values are still made by the
        callbacks, in the same order as one by one); kept in :attr:`plans`."""
        below, state, typ = key
        actions, gotos, rules, unit = self.actions, self.gotos, self.rules, self.unit
        callbacks = []
        while True:
            action = actions[state].get(typ)
            if action is None or action >= 0 or rules[~action][1] != 1:
                break
            origin, _, callback, _ = rules[~action]
            if not unit[~action]:
                callbacks.append(callback)
            state = gotos[below][origin]
        plan = self.plans[key] = (tuple(callbacks), state, action)
        return plan

    def parse(self, text: str, start: str):
        """The builder's result for ``text`` from start symbol ``start``; raises
        :class:`_Slow` (or the builder's exception) where Lark must decide.

        The table is :attr:`actions` (per state: terminal -> the next state when >= 0,
        else the complement ``~i`` of rule ``i`` to reduce by) and :attr:`gotos` (per
        state: rule origin -> next state). A run of one-symbol reductions is followed by
        one lookup in :attr:`plans` (:meth:`_plan`)."""
        stop = self.chunk_stop
        if stop is not None and stop(text) is None:
            toks = self._tokens_by_chunk(text)
        else:
            toks = self._tokens(text)
        actions, gotos, rules = self.actions, self.gotos, self.rules
        single, plans = self.single, self.plans
        state = self.start_states[start]
        state_stack = [state]
        value_stack = []
        for tok in toks:
            typ = tok[0]
            action = actions[state].get(typ)
            while True:
                if action is None:
                    raise _Slow(typ)
                if action >= 0:
                    state = action
                    state_stack.append(state)
                    value_stack.append(tok)
                    break
                if single[~action]:
                    key = (state_stack[-2], state, typ)
                    plan = plans.get(key) or self._plan(key)
                    callbacks, state, action = plan
                    state_stack[-1] = state
                    if callbacks:
                        value = value_stack[-1]
                        for callback in callbacks:
                            value = callback([value])
                        value_stack[-1] = value
                    continue
                origin, size, callback, up = rules[~action]
                if up:
                    value = value_stack[up]
                    del value_stack[-size:]
                elif size:
                    value = callback(value_stack[-size:])
                    del value_stack[-size:]
                else:
                    value = callback([])
                if size:
                    del state_stack[-size:]
                state = gotos[state_stack[-1]][origin]
                state_stack.append(state)
                value_stack.append(value)
                action = actions[state].get(typ)
        return self._finish(state, state_stack, value_stack, start)

    def _finish(self, state: int, state_stack: list, value_stack: list, start: str):
        """The reductions on the end of the text, up to the start symbol's value."""
        actions, gotos, rules = self.actions, self.gotos, self.rules
        end_state = self.end_states[start]
        while True:
            action = actions[state].get("$END")
            if action is None or action >= 0:
                raise _Slow("$END")
            origin, size, callback, up = rules[~action]
            if up:
                value = value_stack[up]
                del value_stack[-size:]
            elif size:
                value = callback(value_stack[-size:])
                del value_stack[-size:]
            else:
                value = callback([])
            if size:
                del state_stack[-size:]
            state = gotos[state_stack[-1]][origin]
            if state == end_state:
                return value
            state_stack.append(state)
            value_stack.append(value)
