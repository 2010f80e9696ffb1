"""Code generation of C99 runtime monitors (``fretc FILE --emit c -o DIR``).

Per requirement file one header and one source (``safe_ros_monitors.h`` / ``.c``; with
``split``, one pair per requirement), rendered from ``templates/c_monitors.h.j2`` and
``templates/c_monitors.c.j2``, and one ``runner.c`` for the folder (``templates/c_runner.c.j2``:
the only ``main``; it reads the audit's CSV traces and prints each requirement's verdict).

Design notes: ARCHITECTURE.md, `compiler/c_codegen.py`."""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from fretc.compiler import ir
from fretc.compiler.automata import LTL3Automata, ltl3_automata
from fretc.compiler.c_step import HELPERS, CField, CStep, c_string, compile_c_nodes
from fretc.compiler.codegen import _env, by_source, file_stems
from fretc.compiler.ir import Node
from fretc.compiler.printers import to_smv
from fretc.compiler.pt_step import CodegenError, check_monitorable
from fretc.compiler.trigger import trigger_pt

if TYPE_CHECKING:
    from fretc.compiler.build import Compiled

__all__ = ["CMonitor", "CUnit", "CodegenError", "c_monitor", "c_units", "emit_c"]


@dataclass
class CAutomaton:
    """One LTL3 automaton of a C monitor: ``field`` (``bad``/``good``), the C name of its
    table (None when it never rejects), initial state, ``empty`` (rejects before any
    tick), ``letter`` (C expression of the atoms' bits) and the status its rejection
    means."""

    field: str
    table: str | None
    initial: int
    empty: bool
    letter: str
    outcome: str


@dataclass
class CInput:
    """One input field: the FRET name as a comment-safe text, the field, its C type, what it
    is, the name as a C string literal and as it is."""

    name: str
    field: str
    ctype: str
    doc: str
    name_c: str
    raw_name: str


@dataclass
class CMonitor:
    """Everything the C templates need for one requirement (module docstring)."""

    prefix: str
    id: str
    text: str
    strings: dict[str, str]
    inputs: list[CInput]
    fields: list[CField]
    pad: int
    state_bytes: int
    lines: list[str]
    commits: list[str]
    nan_expr: str | None
    verdict: str
    quiet: str | None
    automata: list[CAutomaton]
    tables: dict[str, tuple[str, list[list[int]]]]
    helpers: set[str]
    uses_first: bool
    numeric: bool
    tick_doc: str
    note: str
    #: with stream variables (FRET definitions through ``pre``, computed by the monitor):
    #: the lines that fill ``reads`` (the variables the requirement reads, ``reads_fields``:
    #: (C type, field)) from the inputs and the streams' state; else empty
    stream_lines: tuple = ()
    reads_fields: tuple = ()

    @property
    def upper(self) -> str:
        """The prefix in upper case, for the macros."""
        return self.prefix.upper()


def _identifier(text: str) -> str:
    safe = re.sub(r"[^A-Za-z0-9_]", "_", text)[:40]
    return safe or "r"


def c_monitor(compiled: Compiled, prefix: str, automata: LTL3Automata | None = None) -> CMonitor:
    """The :class:`CMonitor` of one compiled requirement (``compiler.build.Compiled``,
    formalized) with C identifier ``prefix``. ``automata``: its LTL3 automata when already
    built (the Python monitor's). Raises :class:`CodegenError` when it has no online
    monitor (pt needs the future) or an LTL3 automaton is given as condition chains."""
    f = compiled.formalization
    assert f is not None  # (a formalized requirement)
    check_monitorable(f.pt)
    if automata is None:
        automata = LTL3Automata(*ltl3_automata(f.ft_inf))
    for aut in (automata.bad, automata.good):
        if aut is not None and aut.table is None and not aut.complete:
            raise CodegenError("an LTL3 automaton over more atoms than a table holds has no "
                               "C code; its status would stay unknown")
    trig = trigger_pt(compiled)
    code = CStep()
    atom_nodes: list[Node] = []  # the atoms of the automata that step (others: unused)
    for aut in (automata.bad, automata.good):
        if aut is not None and not aut.complete and not aut.empty:
            atom_nodes += [a for a in aut.atoms if a not in atom_nodes]
    roots = [f.pt] + atom_nodes + ([trig] if trig is not None else [])
    exprs = compile_c_nodes(roots, code)
    verdict, atom_exprs = exprs[0], exprs[1:1 + len(atom_nodes)]
    quiet = exprs[-1] if trig is not None else None
    reads = _read_lines(code)
    auts, tables = _automata(automata, atom_nodes, atom_exprs, prefix)
    fields = _layout(_fixed_fields(auts, quiet is not None) + code.fields)
    size = sum(x.size for x in fields)
    pad = (-size) % 8
    inputs = _inputs(code, f)
    system = getattr(compiled.entry, "streams", None)
    streams: dict = {}
    if system is not None:
        inputs, streams, extra = _c_streams(system, code, inputs)
        fields = _layout(fields + extra)
        size = sum(x.size for x in fields)
        pad = (-size) % 8
    return CMonitor(
        prefix=prefix, id=compiled.id, text=compiled.text,
        strings=_strings(compiled, automata.note), inputs=inputs, **streams,
        fields=fields, pad=pad, state_bytes=size + pad, lines=reads + code.lines,
        commits=code.commits,
        nan_expr=" || ".join(dict.fromkeys(code.nan_checks)) or None,
        verdict=verdict, quiet=quiet, automata=auts, tables=tables, helpers=code.helpers,
        uses_first=code.uses_first,
        numeric=any(t == "double" for _, t in code.inputs.values()) or bool(code.helpers)
        or any(x.ctype == "double" for x in fields),
        tick_doc=_tick_doc(compiled), note=automata.note)


def _fixed_fields(auts: list[CAutomaton], has_quiet: bool) -> list[CField]:
    """The fields of every state: ticks, LTL3 state, the last verdicts (``quiet`` stays
    false without a trigger formula: never vacuous, as the audit without interval
    evidence)."""
    state = {a.field: str(a.initial) for a in auts}
    status = next((a.outcome for a in auts if a.empty), "FRETC_LTL3_UNKNOWN")
    return [
        CField("uint64_t", "tick", 0, "0u", "ticks stepped"),
        CField("int64_t", "ltl3_tick", 0, "-1", "tick at which ltl3 became definite, -1: "
               "none or before any tick"),
        CField("int64_t", "unread_tick", 0, "-1", "the unread tick that stopped the monitor, "
               "-1: none"),
        CField("int32_t", "bad", 0, state.get("bad", "-2"), "state of the LTL3 automaton "
               "whose rejection means violated (-1 rejected, -2 none)"),
        CField("int32_t", "good", 0, state.get("good", "-2"), "state of the LTL3 automaton "
               "whose rejection means satisfied (-1 rejected, -2 none)"),
        CField("uint8_t", "status", 0, status, "the LTL3 verdict (fretc_ltl3)"),
        CField("bool", "last", 0, "false", "the pt verdict at the last tick"),
        CField("bool", "quiet", 0, "true" if has_quiet else "false",
               "no trigger so far (vacuous if it holds)"),
    ]


def _read_lines(code: CStep) -> list[str]:
    """The locals of the boolean reads (``b_vK``): the input itself, or for a number read
    as a condition ``!= 0`` with NaN an unread tick (:mod:`fretc.monitors.nan`)."""
    out = []
    for field, ctype in code.inputs.values():
        if field not in code.bool_reads:
            continue
        if ctype == "double":
            out.append(f"const bool b_{field} = in->{field} != 0.0;")
            code.nan_checks.insert(0, f"isnan(in->{field})")
        else:
            out.append(f"const bool b_{field} = in->{field};")
    if code.uses_first:
        out.insert(0, "const bool first = s->tick == 0u;")
    return out


def _automata(automata: LTL3Automata, atom_nodes, atom_exprs, prefix: str):
    """The :class:`CAutomaton` list (bad first) and the tables they use."""
    out, tables = [], {}
    for which, aut, outcome in (("bad", automata.bad, "FRETC_LTL3_VIOLATED"),
                                ("good", automata.good, "FRETC_LTL3_SATISFIED")):
        if aut is None:
            continue
        live = not aut.complete and not aut.empty and aut.table is not None
        name, letter = None, "0u"
        if live and aut.table is not None:  # (live: it has a table)
            bits = [atom_exprs[atom_nodes.index(a)] for a in aut.atoms]
            letter = " | ".join(f"({b} ? {1 << j}u : 0u)" for j, b in enumerate(bits)) or "0u"
            name = f"{prefix}_{which}"
            ctype = "int16_t" if len(aut.table) < 32767 else "int32_t"
            tables[name] = (ctype, aut.table)
        out.append(CAutomaton(which, name, aut.initial, aut.empty, letter, outcome))
    return out, tables


def _layout(fields: list[CField]) -> list[CField]:
    """The fields largest element first: no padding between them on any common ABI (a
    stable sort: the fixed fields first within a size)."""
    return sorted(fields, key=lambda x: -(x.size // max(x.length, 1)))


def _inputs(code: CStep, f) -> list[CInput]:
    cmps = [n for n in ir.walk(f.pt) if n.op == "cmp"]
    out = []
    for name, (field, ctype) in code.inputs.items():
        if ctype == "bool":
            doc = "boolean: true or false"
        else:
            uses = sorted({_comment(to_smv(c)) for c in cmps
                           if any(x.op in ("var", "fn") and (x.name == name or to_smv(x) == name)
                                  for x in ir.walk(c))})[:4]
            doc = ("number (IEEE double) in the unit of the requirement's literals: fretc "
                   "carries no units (a binding reads a field in its message's unit)"
                   + (f"; compared in {', '.join(uses)}" if uses else "")
                   + "; NaN in a comparison makes the tick unread")
        out.append(CInput(_comment(name), field, ctype, doc, c_string(name), name))
    return out


def _c_streams(system, code: CStep, reads: list[CInput]
               ) -> tuple[list[CInput], dict, list[CField]]:
    """For a requirement reading the stream variables of ``system``
    (:class:`fretc.fretish.fret_streams.StreamSystem`): its inputs (``reads`` without the
    stream variables, then the variables they read, ``w0``, ``w1``, ... where not read
    already), the :class:`CMonitor` fields ``stream_lines`` and ``reads_fields``, and the
    state fields of the streams' ``pre`` (``q_s0``, ...). A NaN input of a stream makes its
    tick unread, as a NaN comparison does (the audit: unknown from there on)."""
    from fretc.compiler.stream_code import c_tick, stream_code

    sc = stream_code(system, "c", "q_")
    inputs = [x for x in reads if x.raw_name not in system.names]
    field_of = {x.raw_name: (x.field, x.ctype) for x in inputs}
    for k, (name, boolean) in enumerate(zip(system.inputs, system.input_booleans)):
        if name not in field_of:
            ctype = "bool" if boolean else "double"
            field_of[name] = (f"w{k}", ctype)
            doc = ("boolean: true or false" if boolean else "number (IEEE double): NaN makes "
                   "the tick unread")
            inputs.append(CInput(_comment(name), f"w{k}", ctype,
                                 f"{doc}; read by {', '.join(system.names)} (FRET's "
                                 "definitions, computed by the monitor)", c_string(name), name))
    nan = [f"isnan(inputs->{field_of[n][0]})" for n in system.inputs
           if field_of[n][1] == "double"]
    lines = ([f"if ({' || '.join(nan)}) {{", "    s->unread_tick = (int64_t)s->tick; "
              "/* unread: a stream's input is NaN */", "    return s->last;", "}"]
             if nan else [])
    lines += ["const bool q_first = s->tick == 0u;", "(void)q_first;"]
    lines += [f"const {'bool' if b else 'double'} {slot} = s->{slot};"
              for slot, _i, b in sc.slots]
    lines += [f"const {field_of[n][1]} {x} = inputs->{field_of[n][0]};"
              for n, x in zip(system.inputs, sc.inputs)]
    lines += c_tick(sc, "", "s->")
    out = dict(zip(system.names, sc.outputs))
    lines += [f"reads.{fld} = {out[name] if name in out else 'inputs->' + fld};"
              for name, (fld, _t) in code.inputs.items()]
    for h in ("fretc_div", "fretc_mod", "fretc_pow"):
        if any(h in line for line in lines):
            code.helpers.add(h)
    state = [CField("bool" if b else "double", slot, 0, init, "the previous value of a pre "
                    "in a stream's definition") for slot, init, b in sc.slots]
    return inputs, {"stream_lines": tuple(lines), "reads_fields": tuple(
        (t, fld) for fld, t in code.inputs.values())}, state


def _tick_doc(compiled) -> str:
    from fretc.common.units import format_period_ms

    period = compiled.entry.tick_period
    ticks = compiled.formalization.ticks
    when = (f"one tick of {format_period_ms(period)} (@tick_period)" if period is not None
            else "one tick (no @tick_period: durations were read as ticks)")
    return when + (f"; the duration is {ticks} ticks" if ticks is not None else "")


def _strings(compiled, note: str) -> dict[str, str]:
    f = compiled.formalization
    return {"ID": c_string(compiled.id), "TEXT": c_string(compiled.text),
            "KEY": c_string(f.key), "FT": c_string(compiled.smv_text["ft"]),
            "FT_INF": c_string(compiled.smv_text["ft_inf"]),
            "PT": c_string(compiled.smv_text["pt"]),
            "SOURCE_HASH": c_string(compiled.source_hash),
            "LTL3_NOTE": c_string(note)}


def _comment(text: str) -> str:
    """A C comment's text: :func:`fretc.common.textsafe.c_comment`, the one C comment escape
    (printable ASCII, no ``*/``, no trigraph)."""
    from fretc.common.textsafe import c_comment

    return c_comment(text)


# --------------------------------------------------------------------------- files
@dataclass
class CUnit:
    """One header/source pair: its file stem, guard and monitors, and what it skipped."""

    stem: str
    source: str
    monitors: list[CMonitor]
    skipped: list[tuple[str, str]]

    @property
    def guard(self) -> str:
        """The header's include guard."""
        return f"FRETC_{self.stem.upper()}_H"

    @property
    def helpers(self) -> list[str]:
        """The C text of the helpers its monitors use, in a fixed order."""
        used = set().union(*(m.helpers for m in self.monitors)) if self.monitors else set()
        return [HELPERS[k] for k in sorted(used)]

    @property
    def numeric(self) -> bool:
        """Some monitor reads a number (the source includes math.h)."""
        return any(m.numeric for m in self.monitors)


def c_units(compiled: Sequence[Compiled], split: bool = False, automata: dict | None = None) -> list[CUnit]:
    """The header/source pairs of ``compiled`` (:func:`emit_c`'s, before rendering): per
    requirement file one :class:`CUnit` (``split``: one per requirement).

    Names are unique across the whole emission, made so deterministically (``_2``, ``_3``
    ... in input order): file names whatever their case (``one/Safe.fret`` and
    ``two/safe.fret``; a case-insensitive file system, and the include guards in upper
    case), and every C identifier of every monitor (``a.fret``'s ``b_c`` and ``a_b.fret``'s
    ``c`` would both be ``a_b_c``)."""
    groups = by_source(compiled)
    stems = file_stems(groups)
    files: set[str] = {"runner"}  # file stems taken, case-folded (runner.c is the runner's)
    idents: set[str] = set()  # identifiers taken by the monitors so far
    units: list[CUnit] = []
    for source, items in groups.items():
        stem = stems[source]
        if not split:
            name = _free(f"{stem}_monitors", lambda n: n.casefold() not in files)
            files.add(name.casefold())
            units.append(_unit(name, source, stem, items, automata, idents))
            continue
        for c in items:
            name = _free(f"{stem}_{_identifier(c.id)}",
                         lambda n: n.casefold() not in files and not _names(n) & idents)
            files.add(name.casefold())
            units.append(_unit(name, source, name, [c], automata, idents, own_prefix=True))
    return units


def _free(base: str, free: Callable[[str], bool]) -> str:
    """``base``, else ``base_2``, ``base_3`` ...: the first name ``free`` accepts."""
    name, k = base, 2
    while not free(name):
        name, k = f"{base}_{k}", k + 1
    return name


def _unit(file_stem: str, source: str, stem: str, items, automata, used: set[str],
          own_prefix: bool = False) -> CUnit:
    """One :class:`CUnit`; ``used``: the identifiers of the emission so far (added to)."""
    monitors: list[CMonitor] = []
    skipped: list[tuple[str, str]] = []
    for c in items:
        if c.formalization is None:
            reason = "free-form" if c.freeform else getattr(c.error, "message", str(c.error))
            skipped.append((c.id, reason))
            continue
        base = stem if own_prefix else f"{stem}_{_identifier(c.id)}"
        prefix = _free(base, lambda n: not _names(n) & used)
        used.update(_names(prefix))
        try:
            got = (automata or {}).get((source, c.id))
            monitors.append(c_monitor(c, prefix, got))
        except CodegenError as exc:
            skipped.append((c.id, str(exc)))
    return CUnit(file_stem, source, monitors, skipped)


#: the identifiers a monitor of prefix P defines: P_<suffix> and the macros P_<SUFFIX> in
#: upper case (templates/c_monitors.{h,c}.j2)
_SUFFIXES = ("inputs", "state", "state_bytes_check", "init", "step", "unread", "ltl3",
             "ltl3_tick", "finish", "verdict", "ticks", "unread_tick", "bad", "good")
_MACROS = ("ID", "TEXT", "KEY", "FT", "FT_INF", "PT", "SOURCE_HASH", "LTL3_NOTE",
           "STATE_BYTES")


def _names(prefix: str) -> set[str]:
    """Every identifier of a monitor of ``prefix`` (two requirements whose ids differ only
    in case or by one of these suffixes must not define the same one)."""
    return ({f"{prefix}_{x}" for x in _SUFFIXES}
            | {f"{prefix.upper()}_{x}" for x in _MACROS})


def emit_c(compiled: Sequence[Compiled], split: bool = False, automata: dict | None = None
           ) -> tuple[dict[str, str], list[tuple[str, str, str]]]:
    """The C files of ``compiled`` (``compiler.build.Compiled`` list): ``({file name: text},
    [(file stem, requirement id, why it has no monitor)])``, in input order: per
    requirement file ``<stem>_monitors.h`` and ``.c`` (``split``: ``<stem>_<id>.h`` and
    ``.c`` per requirement), then ``runner.c``. ``automata`` maps ``(source, id)`` to LTL3
    automata already built. Same input, same bytes."""
    env = _env()
    env.filters.setdefault("cstr", c_string)
    env.filters.setdefault("ccom", _comment)
    units = c_units(compiled, split, automata)
    files: dict[str, str] = {}
    skipped = []
    for u in units:
        files[f"{u.stem}.h"] = env.get_template("c_monitors.h.j2").render(u=u)
        files[f"{u.stem}.c"] = env.get_template("c_monitors.c.j2").render(u=u)
        skipped += [(u.stem, rid, why) for rid, why in u.skipped]
    monitors = [m for u in units for m in u.monitors]
    files["runner.c"] = env.get_template("c_runner.c.j2").render(
        units=units, monitors=monitors,
        max_inputs=max([1] + [len(m.inputs) for m in monitors]))
    return files, skipped

