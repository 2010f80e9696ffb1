"""The validation suite's checks of the grammar, FRET's semantics and the generated Python
monitors, in this process, against :mod:`fretc.qualification.reference` (FRET's definitions
evaluated directly) and against truth tables written here.

Each check is a :class:`Check`: a name, the tool operational requirements it shows (ids of
``requirements.toml``) and a function of a :class:`Run` returning its failures (a list of
sentences, empty when it passes). A check never raises for a failure of fretc: an exception
escaping it is counted as its failure (:func:`fretc.qualification.suite.run_checks`), but
:class:`CheckSkipped`, raised when the machine lacks what the check needs.
"""

from __future__ import annotations

import random
import types
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from fretc.qualification import reference as ref

#: random traces per template key of the in-process semantic checks
TRACES_PER_KEY = 24
#: the longest random trace, in ticks
MAX_TRACE = 9
#: the seed of every random draw of the suite (its results are the same on every run)
SEED = 20261128


@dataclass
class Run:
    """What the checks of one validation run share: ``work``, the folder they may write in
    (inside the report's folder), ``command`` (the ``fretc`` click group the end-to-end
    checks run, passed in by the command line, which comes after this package) and what
    they built once (the 288 key sentences compiled, random traces)."""

    work: Path
    command: Any = None
    _memo: dict[str, Any] = field(default_factory=dict)

    def memo(self, name: str, make: Callable[[], Any]) -> Any:
        """``make()`` once per run under ``name``."""
        if name not in self._memo:
            self._memo[name] = make()
        return self._memo[name]


class CheckSkipped(Exception):
    """A check that cannot run on this machine (what it needs is missing: a C compiler);
    the message says what. The requirements it shows stay unchecked here."""


@dataclass(frozen=True)
class Check:
    """One check: ``name`` (a stable word), ``tors`` (the requirement ids it shows),
    ``what`` (one sentence for the report) and ``run(Run) -> [failure, ...]``."""

    name: str
    tors: tuple[str, ...]
    what: str
    run: Callable[[Run], list[str]]


def _entry(rid: str, text: str, tick_period: Fraction | None = None) -> Any:
    """A requirement entry as :mod:`fretc.fretish.files` makes one (without a file)."""
    from fretc.fretish import parse

    return SimpleNamespace(id=rid, text=text, source="qualify.fret", line=1, column=1,
                           rationale=None, parent=None, tick_period=tick_period,
                           requirement=parse(text), error=None, extra={})


def compiled_keys(run: Run) -> list[tuple[str, Any]]:
    """``[(key, Compiled)]`` of the 288 key sentences (ids ``K000`` ...), compiled once."""
    from fretc.compiler.build import compile_entry

    def make() -> list[tuple[str, Any]]:
        return [(key, compile_entry(_entry(f"K{i:03d}", text)))
                for i, (key, text) in enumerate(ref.key_sentences())]
    return run.memo("compiled", make)


def traces(run: Run) -> list[list[dict[str, bool]]]:
    """The random traces the in-process checks use, the same on every run (:data:`SEED`)."""
    def make() -> list[list[dict[str, bool]]]:
        rnd = random.Random(SEED)
        return [ref.random_trace(rnd, rnd.randint(1, MAX_TRACE)) for _ in range(TRACES_PER_KEY)]
    return run.memo("traces", make)


def _capped(failures: list[str], limit: int = 5) -> list[str]:
    """The first ``limit`` failures, and how many more."""
    if len(failures) <= limit:
        return failures
    return failures[:limit] + [f"... and {len(failures) - limit} more"]


def check_keys(run: Run) -> list[str]:
    """Every key sentence parses and gets FRET's template key (``scope,condition,timing,
    satisfaction``); keywords in capitals and a final period change nothing."""
    from fretc.compiler.build import compile_entry

    out = []
    for key, c in compiled_keys(run):
        if c.error is not None:
            out.append(f"{key}: {c.error}")
        elif c.to_json()["key"] != f"{key},satisfaction":
            out.append(f"{key}: fretc's key is {c.to_json()['key']}")
    text = "IN m UPON c THE sw SHALL WITHIN 2 TICKS SATISFY r."
    got = compile_entry(_entry("U", text)).to_json()["key"]
    if got != "in,regular,within,satisfaction":
        out.append(f"{text!r}: key {got}")
    return _capped(out)


#: (response text, its meaning as written here from the precedence of
#: docs/reference/semantics.md: ``!``, ``&``, ``|``, ``xor``, ``->`` right-associative,
#: ``<->``; ``if A then B`` extends as far right as possible; ``~`` is negation)
PRECEDENCE: tuple[tuple[str, Callable[..., bool]], ...] = (
    ("a | b & c", lambda a, b, c, d: a or (b and c)),
    ("!a & b", lambda a, b, c, d: (not a) and b),
    ("a xor b | c", lambda a, b, c, d: a != (b or c)),
    ("a -> b -> c", lambda a, b, c, d: (not a) or ((not b) or c)),
    ("a <-> b -> c", lambda a, b, c, d: a == ((not b) or c)),
    ("a & if b then c | d", lambda a, b, c, d: a and ((not b) or (c or d))),
    ("~a | b", lambda a, b, c, d: (not a) or b),
    ("a => b <=> c", lambda a, b, c, d: ((not a) or b) == c),
)


def check_precedence(run: Run) -> list[str]:
    """Each response of :data:`PRECEDENCE`, as ``the sw shall immediately satisfy ...`` on
    every one-tick trace, is true exactly where its meaning is (ft at 0 and pt at the end)."""
    from fretc.compiler.build import compile_entry
    from fretc.compiler.evaluate import ft_at, pt_at

    out = []
    for text, meaning in PRECEDENCE:
        c = compile_entry(_entry("P", f"the sw shall immediately satisfy {text}"))
        if c.formalization is None:
            out.append(f"{text!r}: not formalized ({c.error})")
            continue
        for bits in range(16):
            vals = [bool(bits >> i & 1) for i in range(4)]
            tick = dict(zip("abcd", vals))
            want = meaning(*vals)
            f = c.formalization
            if ft_at(f.ft, [tick]) != want or pt_at(f.pt, [tick]) != want:
                out.append(f"{text!r} at {tick}: fretc reads {not want}, expected {want}")
                break
    return out


#: sentences with a syntax error: (text, the column the error must name)
BAD_SENTENCES = (
    ("the sw shall satisfy", 21),
    ("upon c the sw shal satisfy r", 15),
    ("the sw shall within 2 ticks satisfy r &", 40),
    ("in m the sw shall satisfy r = = 1", 31),
)


def check_syntax_errors(run: Run) -> list[str]:
    """A sentence that does not parse raises fretc's syntax error naming its file, line and
    column (``file:line:col: error: ...``), never another exception; a quoted sentence is
    free form, kept and not formalized."""
    from fretc.common.errors import FretishSyntaxError
    from fretc.fretish import parse

    out = []
    for text, col in BAD_SENTENCES:
        try:
            parse(text, source="q.fret", line=7)
            out.append(f"{text!r} was accepted")
        except FretishSyntaxError as exc:
            if not str(exc).startswith(f"q.fret:7:{col}: error:"):
                out.append(f"{text!r}: {str(exc).splitlines()[0]!r}, expected q.fret:7:{col}")
    free = parse('"the robot is safe"')
    if not free.freeform or free.response is not None:
        out.append("a quoted sentence was formalized")
    return out


def check_formulas(run: Run) -> list[str]:
    """For every key and trace: ft at the first position and pt at the last give FRET's
    finite-trace truth (the reference's verdict is not ``violated``)."""
    from fretc.compiler.evaluate import ft_at, pt_at

    out = []
    for key, c in compiled_keys(run):
        for trace in traces(run):
            want = ref.verdict(key, trace) != "violated"
            f = c.formalization
            ft, pt = ft_at(f.ft, trace), pt_at(f.pt, trace)
            if ft != want or pt != want:
                out.append(f"{key} on {_text(trace)}: ft {ft}, pt {pt}, expected {want}")
                break
    return _capped(out)


def check_judge(run: Run) -> list[str]:
    """For every key and trace: the audit's judge (FRET's interval semantics over columns,
    :func:`fretc.monitors.interval.verdict_of`) gives the reference's verdict, vacuous
    included."""
    import numpy as np

    from fretc.monitors.interval import verdict_of

    out = []
    for key, c in compiled_keys(run):
        for trace in traces(run):
            cols = {v: np.array([t[v] for t in trace], dtype=np.bool_) for v in ref.VARIABLES}
            got, want = verdict_of(c.requirement, cols, len(trace)), ref.verdict(key, trace)
            if got != want:
                out.append(f"{key} on {_text(trace)}: the judge says {got}, expected {want}")
                break
    return _capped(out)


def check_monitors(run: Run) -> list[str]:
    """For every key and trace: the generated Python monitor (``--emit monitor``'s module,
    loaded here), stepped tick by tick, ends with FRET's finite-trace truth (``finish()``)."""
    from fretc.compiler.codegen import render_module

    comps = compiled_keys(run)
    module = types.ModuleType("qualify_monitors")
    exec(compile(render_module([c for _, c in comps], "qualify_monitors"),  # noqa: S102
                 "<qualify_monitors>", "exec"), module.__dict__)
    out = []
    for key, c in comps:
        for trace in traces(run):
            monitor = module.MONITORS[c.id]()
            for tick in trace:
                monitor.step(dict(tick))
            want = ref.verdict(key, trace) != "violated"
            got = monitor.finish()
            if got != want:
                out.append(f"{key} on {_text(trace)}: monitor {got}, expected {want}")
                break
    return _capped(out)


def check_durations(run: Run) -> list[str]:
    """A duration in time units converts with the tick period (``within 1 second`` at 100 ms
    is 10 ticks); one that is not a whole number of ticks is an error naming it."""
    from fretc.common.errors import FretcError
    from fretc.compiler.semantics import formalize
    from fretc.fretish import parse

    out = []
    tenth = Fraction(1, 10)
    f = formalize(parse("upon c the sw shall within 1 second satisfy r"), tenth)
    if f.ticks != 10:
        out.append(f"'within 1 second' at 100 ms is {f.ticks} ticks, expected 10")
    try:
        formalize(parse("upon c the sw shall within 150 milliseconds satisfy r"), tenth)
        out.append("'within 150 milliseconds' at 100 ms was accepted (1.5 ticks)")
    except FretcError as exc:
        if "150 milliseconds" not in str(exc):
            out.append(f"the error does not name the duration: {exc}")
    return out


#: sentences FRET formalizes wrongly and fretc refuses (docs/reference/semantics.md, FRET's
#: defects 3, 6 and 7): each with words the error must hold
REFUSED = (("the sw shall immediately satisfy preBool(0, p)", "preBool"),
           ("the sw shall immediately satisfy persisted(2, 0, p)", "lower bound 2"),
           ("the sw shall immediately satisfy absReal(x, y) > 1", "absReal takes 1"))


def check_fret_forms(run: Run) -> list[str]:
    """FRET's names in the formulas (``a.b`` as ``a_DOT_b``, a quoted name character by
    character); a probability's five-part key and its LTL key; the FRET defects fretc does
    not copy refused with an error naming the fault."""
    from fretc.common.errors import FretcError
    from fretc.compiler.build import compile_entry

    out = []
    ft = compile_entry(_entry("N", 'the sw shall immediately satisfy a.b & "weird var"')
                       ).to_json()["ft"]
    if ft != "(a_DOT_b & _DQT_weird_SPC_var_DQT_)":
        out.append(f"names: ft {ft!r}, expected FRET's (a_DOT_b & _DQT_weird_SPC_var_DQT_)")
    doc = compile_entry(_entry(
        "P", "upon c the sw shall, with probability >= 0.9, within 1 tick satisfy r")).to_json()
    if (doc["key"], doc.get("key_ltl")) != ("null,regular,bound,within,satisfaction",
                                            "null,regular,within,satisfaction"):
        out.append(f"probability: keys {doc['key']}, {doc.get('key_ltl')}")
    for text, words in REFUSED:
        error: Exception | None
        try:
            error = compile_entry(_entry("D", text)).error
        except FretcError as exc:
            error = exc
        if error is None or words not in str(error):
            out.append(f"{text!r}: {error!r}, expected an error naming {words!r}")
    return out


#: random words per key of the ft_inf check
INF_WORDS = 4
#: all-false ticks after a finite trace that stand for its infinite all-false tail in the
#: reference (more than any bound of the key sentences can reach)
INF_TAIL = 3 * ref.DURATION + 2


def check_ft_inf(run: Run) -> list[str]:
    """For every key but ``finally`` and random traces: the ft_inf formula accepts the
    infinite word of the trace followed by the absorbing all-false state (Spot) exactly when
    the reference's verdict on the trace followed by :data:`INF_TAIL` all-false ticks is not
    violated. (``finally`` is the scope's last tick, which an open scope of an infinite word
    does not have.)"""
    try:
        import spot
    except ImportError as exc:
        raise CheckSkipped(f"Spot is not installed ({exc})") from None
    from fretc.compiler.printers import to_spot
    from fretc.compiler.semantics import formalize
    from fretc.fretish import parse

    rnd = random.Random(SEED + 7)
    quiet = {v: False for v in ref.VARIABLES}
    tail = "cycle{" + " & ".join(f"!{v}" for v in ref.VARIABLES) + "}"
    out = []
    for key, text in ref.key_sentences():
        if key.endswith(",finally"):
            continue
        aut = spot.translate(spot.formula(to_spot(formalize(parse(text)).ft_inf)))
        for _ in range(INF_WORDS):
            trace = ref.random_trace(rnd, rnd.randint(1, MAX_TRACE))
            letters = [" & ".join(v if t[v] else f"!{v}" for v in ref.VARIABLES)
                       for t in trace]
            word = spot.parse_word("; ".join([*letters, tail]))
            got = bool(aut.intersects(word.as_automaton()))
            want = ref.verdict(key, trace + [quiet] * INF_TAIL) != "violated"
            if got != want:
                out.append(f"{key} on {_text(trace)} then all false: ft_inf "
                           f"{'accepts' if got else 'rejects'}, the reference says "
                           f"{'holds' if want else 'violated'}")
                break
    return _capped(out)


def _fn_persisted(p: list[bool], t: int, s: int, e: int) -> bool:
    return t - 2 >= s and all(p[t - 2:t + 1])


def _fn_occurred(p: list[bool], t: int, s: int, e: int) -> bool:
    return any(p[max(s, t - 2):t + 1])


def _fn_persists(p: list[bool], t: int, s: int, e: int) -> bool:
    return t + 2 <= e and all(p[t:t + 3])


def _fn_occurs(p: list[bool], t: int, s: int, e: int) -> bool:
    return any(p[t:min(t + 2, e) + 1])


#: the temporal functions (docs/reference/semantics.md's table), each with its meaning at
#: tick t of the scope interval [s, e] over the response's column p (n = 2) and q
FUNCTIONS: dict[str, Callable[[list[bool], list[bool], int, int, int], bool]] = {
    "persisted(2, p)": lambda p, q, t, s, e: _fn_persisted(p, t, s, e),
    "occurred(2, p)": lambda p, q, t, s, e: _fn_occurred(p, t, s, e),
    "persists(2, p)": lambda p, q, t, s, e: _fn_persists(p, t, s, e),
    "occurs(2, p)": lambda p, q, t, s, e: _fn_occurs(p, t, s, e),
    "prevOcc(p, q)": lambda p, q, t, s, e: t == s or next(
        (q[j] for j in range(t - 1, s - 1, -1) if p[j]), True),
    "nextOcc(p, q)": lambda p, q, t, s, e: t == e or next(
        (q[j] for j in range(t + 1, e + 1) if p[j]), True),
    "preBool(true, p)": lambda p, q, t, s, e: True if t == 0 else p[t - 1],
}


def check_functions(run: Run) -> list[str]:
    """Each temporal function in a response (``always satisfy F``), without a scope and in
    ``in m mode`` (the scope intervals the maximal runs of m), on random traces: the judge's
    verdict is satisfied exactly when F holds at every tick of every interval, F evaluated
    as docs/reference/semantics.md's table says relative to the interval's ends."""
    import numpy as np

    from fretc.compiler.build import compile_entry
    from fretc.monitors.interval import verdict_of

    rnd = random.Random(SEED + 9)
    out = []
    for text, meaning in FUNCTIONS.items():
        for scoped in (False, True):
            sentence = f"{'in m mode ' if scoped else ''}the sw shall always satisfy {text}"
            req = compile_entry(_entry("F", sentence)).requirement
            if req is None:
                out.append(f"{sentence!r} does not compile")
                continue
            for _ in range(TRACES_PER_KEY):
                n = rnd.randint(1, MAX_TRACE)
                cols = {v: [rnd.random() < 0.6 for _ in range(n)] for v in ("p", "q", "m")}
                if not scoped:
                    cols["m"] = [True] * n
                runs, t = [], 0
                while t < n:
                    if cols["m"][t]:
                        s = t
                        while t + 1 < n and cols["m"][t + 1]:
                            t += 1
                        runs.append((s, t))
                    t += 1
                holds = all(meaning(cols["p"], cols["q"], k, s, e)
                            for s, e in runs for k in range(s, e + 1))
                want = ("satisfied" if holds else "violated") if runs else "vacuous"
                got = verdict_of(req, {v: np.array(x, dtype=np.bool_)
                                                 for v, x in cols.items()}, n)
                if got != want:
                    out.append(f"{sentence!r} on p={_bits(cols['p'])} q={_bits(cols['q'])} "
                               f"m={_bits(cols['m'])}: {got}, expected {want}")
                    break
    return _capped(out)


def _bits(xs: Iterable[int]) -> str:
    """A column as 0s and 1s."""
    return "".join("1" if x else "0" for x in xs)


def _text(trace: list[dict[str, bool]]) -> str:
    """A trace as one word per tick: the variables true there (``-`` for none)."""
    return " ".join("".join(v for v in ref.VARIABLES if t[v]) or "-" for t in trace)


#: the in-process checks, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("grammar-keys", ("TOR-GRM-001", "TOR-SEM-001"),
          "the 288 key sentences parse to FRET's template keys", check_keys),
    Check("grammar-precedence", ("TOR-GRM-003",),
          "operator precedence and grouping by truth tables", check_precedence),
    Check("grammar-errors", ("TOR-GRM-002", "TOR-GRM-004"),
          "syntax errors at file:line:col; free-form sentences kept", check_syntax_errors),
    Check("semantics-formulas", ("TOR-SEM-002", "TOR-SEM-003"),
          "ft and pt of every key against the reference evaluator", check_formulas),
    Check("semantics-ft-inf", ("TOR-SEM-004",),
          "ft_inf of every key on infinite words against the reference", check_ft_inf),
    Check("semantics-functions", ("TOR-SEM-008",),
          "the temporal functions against their table, relative to the scope",
          check_functions),
    Check("semantics-judge", ("TOR-SEM-005", "TOR-SEM-006", "TOR-SEM-007"),
          "the audit's judge on every key against the reference evaluator", check_judge),
    Check("monitors-python", ("TOR-GEN-001",),
          "generated Python monitors on every key against the reference", check_monitors),
    Check("semantics-durations", ("TOR-SEM-010",),
          "durations convert with the tick period, exactly", check_durations),
    Check("semantics-fret-forms", ("TOR-SEM-009", "TOR-SEM-011", "TOR-SEM-012"),
          "FRET's names, a probability's keys, FRET's defects refused", check_fret_forms),
)
