"""Code generation of standalone Python runtime monitors (``fretc FILE --emit monitor``).

One module per requirement file, rendered from ``templates/monitor_module.py.j2``. The module
imports only the standard library and exposes ``MONITORS: dict[str, type]``; each monitor
class has ``VARIABLES``, ``step(sample) -> bool``, ``status``, ``finish() -> bool`` and
``reset()`` (see the template's docstring).

Design notes: ARCHITECTURE.md, `compiler/codegen.py`."""

from __future__ import annotations

import functools
import hashlib
import opcode
import re
import sys
import types
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from fretc.common import cache as fretc_cache
from fretc.compiler import code_cache, text_cache
from fretc.compiler.automata import Automaton, LTL3Automata, ltl3_automata
from fretc.compiler.build import Compiled
from fretc.compiler.ir import Node
from fretc.compiler.pt_step import CodegenError, StepCode, check_monitorable, compile_nodes

__all__ = ["CodegenError", "InvalidMonitorError", "MonitorInfo", "MonitorModule",
           "MonitorSource", "build_monitor_modules", "check_module", "emit_monitors",
           "encode_table", "file_stems", "monitor_source", "render_module"]


# --------------------------------------------------------------------------- per requirement
@dataclass
class MonitorSource:
    """Everything the template needs for one requirement's monitor class: the requirement's
    identity and formulas (FRET syntax), the tick code (:class:`fretc.compiler.pt_step.StepCode`
    pieces: ``step_lines``, the state tuple's ``slots_*``, the local of the pt ``verdict``)
    and the LTL3 ``automata`` with the Python code of each automaton's letter
    (``bad_sub``, ``good_sub``: an int of the atom bits, or for condition chains the tuple
    of the atoms' values)."""

    index: int
    class_name: str
    id: str
    text: str
    key: str
    ft: str
    ft_inf: str
    pt: str
    source_hash: str
    variables: list[str]
    var_locals: list[tuple[str, str, bool, bool]]
    slots_init: str
    slots_unpack: str
    slots_next: str
    slots_unpack_run: str
    slots_loop_next: str
    slots_run_end: str
    step_lines: list[str]
    verdict: str
    atom_locals: list[str]
    automata: LTL3Automata
    uses_first: bool
    bad_sub: str = "0"
    good_sub: str = "0"
    bad_table: int | None = None  # index in the module's _TABLES (render_module)
    good_table: int | None = None
    shape: int | None = None  # index in the module's _SHAPES (render_module)
    #: a probability requirement's PCTL (FRET's bounds at each trigger around ft_inf,
    #: :mod:`fretc.compiler.pctl`), else None: the monitor judges the path formula on one
    #: run; the bound applies to each trigger across runs
    pctl: str | None = None
    probability: tuple | None = None  # (op, p) of the bound, with pctl
    #: the named durations' values used (``["T_stop = 1.5 seconds"]``), else empty
    constants: tuple = ()
    #: the stream variables it reads (FRET's definitions through ``pre``: the entry's
    #: ``streams``), computed by the monitor: the source of their factory
    #: (:func:`fretc.compiler.stream_code.python_factory`), its arguments (the inputs'
    #: names, then the stream variables'), and the monitor's inputs (``VARIABLES``: the
    #: variables it reads with the stream variables' inputs in their place); else empty
    stream_source: str = ""
    stream_args: tuple = ()
    inputs: tuple = ()

    # read-only delegations, same shape as compiler.build.Compiled's (kept: one property per field)
    @property
    def bad(self) -> Automaton | None:
        """The automaton whose rejection means *violated* (or None)."""
        return self.automata.bad

    @property
    def good(self) -> Automaton | None:
        """The automaton whose rejection means *satisfied* (or None)."""
        return self.automata.good

    @property
    def status_note(self) -> str:
        """Why the LTL3 status is limited ("" when Spot built both automata)."""
        return self.automata.note

    @property
    def verdict_expr(self) -> str:
        """The verdict as a Python bool: locals computed from boolean reads are bools
        already; numeric reads may bring other types (e.g. numpy scalars)."""
        if any(numeric for _, _, numeric, _ in self.var_locals) or self.verdict in (
                "True", "False", "first"):
            return f"bool({self.verdict})"
        return self.verdict

    @property
    def stream_close(self) -> str:
        """The end of the class's line in the module: the stream variables' factory and
        the monitor's inputs after its own monitor class (``""`` without streams)."""
        if not self.stream_source:
            return ""
        return f", _streams_{self.index}(*{self.stream_args!r}), {self.inputs!r})"

    @property
    def status_live(self) -> bool:
        """Can the status still change after reset()? (some automaton can reject)"""
        return any(a is not None and not a.complete for a in (self.good, self.bad))


def _constant_notes(compiled) -> list[str]:
    """The named durations of ``compiled``'s requirement with their values."""
    req = compiled.requirement
    d = req.timing.duration if req is not None and not req.freeform else None
    if d is None or d.name is None:  # (attributes only: the main line of plain requirements)
        return []
    from fretc.fretish.constants import constant_notes

    return constant_notes(req)


def _class_name(rid: str, index: int) -> str:
    safe = re.sub(r"[^A-Za-z0-9_]", "_", rid)[:40]
    return f"Monitor_{safe}_{index}"


def monitor_source(compiled: Compiled, index: int) -> MonitorSource:
    """Generate the code pieces of one compiled requirement (``compiler.build.Compiled``,
    formalized), the ``index``-th of its module. Raises :class:`CodegenError` when no
    monitor can be built (pt needs the future)."""
    f = compiled.formalization
    assert f is not None  # (a formalized requirement)
    check_monitorable(f.pt)  # before any expensive work
    code = StepCode()
    bad, good, note = ltl3_automata(f.ft_inf)
    automata = LTL3Automata(bad, good, note)
    atom_nodes = automata.atoms
    locals_ = compile_nodes([f.pt] + atom_nodes, code)
    verdict, atom_locals = locals_[0], locals_[1:]
    var_locals = [(name, local, local in code.numeric_reads, local in code.bool_reads)
                  for name, local in code.variables.items()]
    # the state tuple: pt slots, then the tick count, then the last verdict
    slots_init = "(" + "".join(f"{init}, " for init, _ in code.slots) + "0, None)"
    slots_next = "(" + "".join(f"{nxt}, " for _, nxt in code.slots) + "tick + 1, verdict)"
    return MonitorSource(
        index=index, class_name=_class_name(compiled.id, index), id=compiled.id,
        text=compiled.text, key=f.key, ft=compiled.smv_text["ft"], ft_inf=compiled.smv_text["ft_inf"],
        pt=compiled.smv_text["pt"], source_hash=compiled.source_hash,
        pctl=compiled.pctl() if getattr(compiled, "probability", None) is not None else None,
        probability=((b.op, b.p)
                     if (b := getattr(compiled, "probability", None)) is not None else None),
        variables=[v[0] for v in var_locals], var_locals=var_locals,
        slots_init=slots_init,
        slots_unpack="".join(f"s{i}, " for i in range(len(code.slots))) + "tick, _",
        slots_next=slots_next, step_lines=code.lines,
        # run(): the slots stay locals across the ticks of the loop
        slots_unpack_run="".join(f"s{i}, " for i in range(len(code.slots))) + "tick, verdict",
        slots_loop_next=(", ".join(f"s{i}" for i in range(len(code.slots))) + " = "
                         + ", ".join(nxt for _, nxt in code.slots)) if code.slots else "",
        slots_run_end="(" + "".join(f"s{i}, " for i in range(len(code.slots)))
                      + "tick, verdict)",
        verdict=verdict, atom_locals=atom_locals, automata=automata,
        uses_first=code.uses_first,
        constants=tuple(_constant_notes(compiled)),
        bad_sub=_letter_code(bad, atom_nodes, atom_locals),
        good_sub=_letter_code(good, atom_nodes, atom_locals),
        **_streams(compiled, index, [v[0] for v in var_locals]))


def _streams(compiled: Compiled, index: int, variables: list[str]) -> dict[str, Any]:
    """The stream fields of :class:`MonitorSource` for a requirement whose entry has
    ``streams`` (:class:`fretc.fretish.fret_streams.StreamSystem`), else none."""
    system = getattr(compiled.entry, "streams", None)
    if system is None:
        return {}
    from fretc.compiler.stream_code import python_factory

    inputs = [v for v in variables if v not in system.names]
    return {"stream_source": python_factory(system, f"_streams_{index}"),
            "stream_args": system.inputs + system.names,
            "inputs": tuple(inputs + [v for v in system.inputs if v not in inputs])}


def _letter_code(aut, atom_nodes: list[Node], atom_locals: list[str]) -> str:
    """Python code of an automaton's letter from the atoms' locals: the int of the atom
    bits (tables), or the tuple of the atoms' values in the automaton's atom order
    (condition chains index it by atom number)."""
    if aut is None:
        return "0"
    idx = [atom_nodes.index(a) for a in aut.atoms]
    if aut.table is not None:
        return " | ".join(f"({1 << j} if {atom_locals[b]} else 0)"
                          for j, b in enumerate(idx)) or "0"
    return "(" + "".join(f"{atom_locals[b]}, " for b in idx) + ")"


# --------------------------------------------------------------------------- modules
@dataclass(frozen=True)
class MonitorInfo:
    """One requirement's monitor in a generated module.

    Attributes:
        class_name: the name of its class in the module (``MONITORS[id]`` is that class).
        source: what the template was fed for it.
        automata: its LTL3 automata (``bad`` / ``good`` may be None, ``note`` says why), the
            same objects the module's tables were written from."""

    class_name: str
    source: MonitorSource
    automata: LTL3Automata


@dataclass(frozen=True)
class MonitorModule:
    """One generated monitor module (one requirement file).

    Attributes:
        name: the module name (``r1_monitors``; :func:`file_stems`).
        text: the module's Python source, as ``fretc --emit monitor`` writes it.
        monitors: requirement id -> its monitor, in the order of ``MONITORS``.
        skipped: requirement id -> why it has no monitor, as the module's ``SKIPPED``."""

    name: str
    text: str
    monitors: dict[str, MonitorInfo]
    skipped: dict[str, str]


_JINJA_MAGIC = b"fretc jinja 2\n"


@functools.lru_cache(maxsize=1)
def _env():
    import jinja2  # lazy: start-up of the commands that render nothing (--emit ltl)

    class BytecodeCache(jinja2.BytecodeCache):
        """Jinja's compiled templates (``marshal`` code) in fretc's disk cache
        (:mod:`fretc.common.cache`: skipped when off, refused or not writable), as sealed
        entries: one altered, damaged or planted is a miss (compiled again), never code that
        runs. Jinja also checks an entry's header (its bytecode format, Python's version) and
        the template source's checksum."""

        def load_bytecode(self, bucket):
            data = fretc_cache.read_sealed("jinja", bucket.key, _JINJA_MAGIC,
                                           fretc_cache.digest(bucket.key.encode()))
            if data is None:
                return
            try:
                bucket.bytecode_from_string(data)
            except Exception:  # noqa: BLE001 - an entry Jinja cannot read is a miss
                bucket.reset()

        def dump_bytecode(self, bucket):
            fretc_cache.write_sealed("jinja", bucket.key, _JINJA_MAGIC,
                                     fretc_cache.digest(bucket.key.encode()),
                                     bucket.bytecode_to_string())

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("fretc.templates", ""),
        keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
        undefined=jinja2.StrictUndefined, autoescape=False, bytecode_cache=BytecodeCache())
    env.filters["py"] = repr
    return env


class InvalidMonitorError(RuntimeError):
    """Internal error: the code generated for a requirement is not a valid, loadable monitor
    (a bug in fretc, never the user's). ``ids`` are the requirements concerned."""

    def __init__(self, message: str, ids=()):
        super().__init__(message)
        self.ids = list(ids)


_ALLOWED_BUILTINS = frozenset(("abs", "min", "max", "bool", "float", "int", "len",
                               "RuntimeError", "KeyError", "ZeroDivisionError",
                               "OverflowError", "ValueError", "complex", "isinstance",
                               "property", "__name__", "type", "tuple", "dict", "str",
                               "exec", "compile", "globals"))


def check_module(text: str, module_name: str, cache: bool = False) -> None:
    """Check a generated module before it is written or loaded: it compiles, every global
    name its code reads is defined by the module or is one of the builtins the template
    uses (so no ``NameError`` can happen at run time), it loads, and every monitor steps
    through two ticks (all variables 0, then 1) and finishes.

    With ``cache``, the code objects of the module and of its shapes come from the disk
    cache when a previous check compiled this very text (:mod:`fretc.compiler.code_cache`; the
    names check, the load and the steps run all the same), and are stored there after a
    check that passed.

    Raises :class:`InvalidMonitorError` (an internal error) naming the failure."""
    _check_module(text, module_name, cache)


def _check_module(text: str, module_name: str, cache: bool) -> None:

    def fail(what, exc=None):
        detail = f": {type(exc).__name__}: {exc}" if exc is not None else ""
        raise InvalidMonitorError(
            f"internal error: the generated monitor module {module_name!r} {what}{detail}; "
            "this is a bug in fretc, please report it with the requirement")

    cached = code_cache.load(module_name, text) if cache else None
    if cached is not None:
        code, shape_codes = cached
    else:
        try:
            code = compile(text, f"<fretc monitors {module_name}>", "exec")
        except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError) as exc:
            fail("does not compile", exc)
        shape_codes = ()
    defined, reads = _names(code)
    unknown = sorted(reads - defined - _ALLOWED_BUILTINS)
    if unknown:
        fail(f"reads undefined names {', '.join(unknown)}")
    ns: dict[str, Any] = {"__name__": module_name}
    compiled_shapes = []
    try:
        exec(code, ns)  # only the standard library and literals made by repr
        for i, shape in enumerate(ns["_SHAPES"]):  # the step code, compiled on first use
            if i < len(shape_codes):
                shape_code = shape_codes[i]
            else:
                shape_code = compile(shape[-1], f"<{module_name} shape {i}>", "exec")
            compiled_shapes.append(shape_code)
            shape_defined, shape_reads = _names(shape_code)
            unknown = sorted(shape_reads - shape_defined - defined - _ALLOWED_BUILTINS)
            if unknown:
                fail(f"reads undefined names {', '.join(unknown)} in shape {i}")
            shape_ns: dict[str, Any] = {}
            exec(shape_code, ns, shape_ns)  # what the module's _bind does, compiled once
            ns["_MAKE"][i] = shape_ns["make"]
        for _rid, cls in ns["MONITORS"].items():
            m = cls()
            for value in (0, 1):
                m.step({v: value for v in cls.VARIABLES})
            m.finish()
    except InvalidMonitorError:
        raise
    except Exception as exc:  # noqa: BLE001 - any failure here is an internal error
        fail("does not load and step", exc)
    if cache and cached is None:
        code_cache.store(module_name, text, code, compiled_shapes)


_EXTENDED_ARG = opcode.EXTENDED_ARG
_STORES = {opcode.opmap[n] for n in ("STORE_NAME", "STORE_GLOBAL", "IMPORT_NAME")}
_LOAD_NAME = opcode.opmap["LOAD_NAME"]
_LOAD_GLOBAL = opcode.opmap["LOAD_GLOBAL"]
#: Python 3.11 moved a flag into the low bit of LOAD_GLOBAL's argument (dis documents it)
_GLOBAL_SHIFT = 1 if sys.version_info >= (3, 11) else 0


def _names(code: types.CodeType) -> tuple[set[str], set[str]]:
    """(names defined at the top level of ``code``, global names its code and functions
    read), from the bytecode's name operations (``dis``'s instruction decoding, without
    ``dis``: it is 20 times slower on the thousands of functions of a large module).

    An instruction is two bytes, opcode then argument, so the opcodes are the even bytes
    of ``co_code``: the name operations are found by ``bytes.find`` on them, and their
    argument is the next byte, extended by the ``EXTENDED_ARG`` prefixes just before
    (a code object of more than 256 names)."""
    defined: set[str] = set()
    reads: set[str] = set()
    stack = [code]
    while stack:
        co = stack.pop()
        names = co.co_names
        if names:
            raw = co.co_code
            ops, args = raw[::2], raw[1::2]
            extended = _EXTENDED_ARG_BYTE in ops
            top = co is code
            for op in (_WANTED_TOP if top else _WANTED):
                i = ops.find(op)
                while i >= 0:
                    arg = args[i]
                    if extended:
                        j, shift = i - 1, 8
                        while j >= 0 and ops[j] == _EXTENDED_ARG:
                            arg |= args[j] << shift
                            j, shift = j - 1, shift + 8
                    if op == _LOAD_GLOBAL:
                        reads.add(names[arg >> _GLOBAL_SHIFT])
                    elif op == _LOAD_NAME:
                        reads.add(names[arg])
                    else:
                        defined.add(names[arg])
                    i = ops.find(op, i + 1)
        stack.extend(c for c in co.co_consts if isinstance(c, types.CodeType))
    return defined, reads


_EXTENDED_ARG_BYTE = bytes([_EXTENDED_ARG])
_WANTED = (_LOAD_GLOBAL, _LOAD_NAME)
_WANTED_TOP = _WANTED + tuple(sorted(_STORES))


def build_monitor_module(compiled_list: Sequence[Compiled], module_name: str,
                         errors: list | None = None) -> MonitorModule:
    """One generated monitor module for a list of compiled requirements
    (``compiler.build.Compiled``, in the module's order); requirements that failed or have
    no monitor are listed in ``SKIPPED`` with the reason.

    The module is checked by :func:`check_module`. Should a requirement's code ever fail
    that check (an internal error), it is listed in ``SKIPPED`` with the error, so the other
    requirements keep their monitors, and the :class:`InvalidMonitorError` is appended to
    ``errors`` when given (``fretc --emit monitor`` then exits non-zero)."""
    monitors: list[MonitorSource] = []
    skipped: list[tuple[str, str]] = []
    for i, c in enumerate(compiled_list):
        if c.formalization is None:
            reason = "free-form" if c.freeform else getattr(c.error, "message", str(c.error))
            skipped.append((c.id, reason))
            continue
        try:
            monitors.append(monitor_source(c, i))
        except CodegenError as exc:
            skipped.append((c.id, str(exc)))
    text = _render(monitors, skipped, module_name)
    try:
        check_module(text, module_name, cache=True)
    except InvalidMonitorError as exc:
        bad = _invalid_monitors(monitors, module_name, exc)
        failed = InvalidMonitorError("; ".join(f"{m.id}: {e}" for m, e in bad),
                                     [m.id for m, _ in bad])
        if errors is not None:
            errors.append(failed)
        skipped += [(m.id, str(e)) for m, e in bad]
        monitors = [m for m in monitors if m not in [b for b, _ in bad]]
        text = _render(monitors, skipped, module_name)
    return MonitorModule(
        name=module_name, text=text,
        monitors={m.id: MonitorInfo(m.class_name, m, m.automata) for m in monitors},
        skipped=dict(skipped))


def _invalid_monitors(monitors: list[MonitorSource], module_name: str,
                      problem: InvalidMonitorError
                      ) -> list[tuple[MonitorSource, InvalidMonitorError]]:
    """The monitors at fault in a module that failed :func:`check_module`, each checked
    alone (all of them, with the module's error, when none fails alone)."""
    bad = []
    for m in monitors:
        try:
            check_module(_render([m], [], module_name), module_name)
        except InvalidMonitorError as exc:
            bad.append((m, exc))
    if not bad:  # pragma: no cover - the module itself is broken
        bad = [(m, problem) for m in monitors]
    return bad


def render_module(compiled_list: Sequence[Compiled], module_name: str, errors: list | None = None) -> str:
    """The text of :func:`build_monitor_module` (same arguments and errors)."""
    return build_monitor_module(compiled_list, module_name, errors).text


def _render(monitors: list[MonitorSource], skipped, module_name: str) -> str:
    digest = hashlib.sha256("\n".join(f"{m.id}:{m.source_hash}" for m in monitors)
                            .encode()).hexdigest()
    tables: dict[str, int] = {}  # encoded table -> index: one copy per distinct table
    encoded: dict[int, str] = {}  # id of a table -> its text (monitors of a shape share one)
    for m in monitors:
        for which in ("bad", "good"):
            aut = getattr(m, which)
            if aut is not None and aut.table is not None and not aut.complete:
                text = encoded.get(id(aut.table))
                if text is None:
                    text = encoded[id(aut.table)] = encode_table(aut.table)
                setattr(m, f"{which}_table", tables.setdefault(text, len(tables)))
    def render() -> str:  # Jinja, when the text is not in the cache (text_cache)
        env = _env()
        shape_template = env.get_template("monitor_shape.py.j2")
        # one shape per distinct (step code, KEY, STATUS_NOTE, tables): the code is rendered
        # without the variable names, so equal text means equal behaviour
        shapes: dict[tuple, int] = {}
        for m in monitors:
            ident = (shape_template.render(m=m), m.key, m.status_note, m.bad_table, m.good_table)
            m.shape = shapes.setdefault(ident, len(shapes))
        return env.get_template("monitor_module.py.j2").render(
            module_name=module_name, monitors=monitors, skipped=skipped, digest=digest,
            tables=list(tables), shapes=[_Shape(key, note, bad, good, _code_literal(code))
                                         for code, key, note, bad, good in shapes])
    return text_cache.rendered(module_name, repr((monitors, skipped, module_name)), monitors, render)


@dataclass(frozen=True)
class _Shape:
    """One entry of a module's ``_SHAPES``: template key, status note, table indices (or
    None) and the step code as a Python string literal."""

    key: str
    note: str
    bad_table: int | None
    good_table: int | None
    literal: str


def _code_literal(code: str) -> str:
    """Generated code as a readable string literal: triple-quoted with its line breaks
    (the code holds no backslash and no triple quote: generated locals, numbers and
    repr'd status words only), else ``repr``."""
    if "\\" in code or "'''" in code or code.endswith("'"):
        return repr(code)
    return "'''\\\n" + code + "'''"


def encode_table(table: list[list[int]]) -> str:
    """A transition table as the generated module stores it: rows separated by ``;``,
    destinations by ``,`` (the module's ``_table`` decodes it)."""
    return ";".join(",".join(map(str, row)) for row in table)


def by_source(compiled: Iterable[Any]) -> dict[str, list]:
    """The compiled requirements grouped by their file (``entry.source``), files and
    requirements in input order: one generated output a file."""
    groups: dict[str, list] = {}
    for c in compiled:
        groups.setdefault(c.entry.source, []).append(c)
    return groups


def file_stems(sources: Iterable[str], suffix: str = "") -> dict[str, str]:
    """A distinct Python-identifier stem per requirement file, in order: the file name's
    stem (``requirements/r1.fret`` -> ``r1`` + ``suffix``), with ``_2``, ``_3`` ... added when
    two files of different folders share a name (so no output overwrites another)."""
    out: dict[str, str] = {}
    used: set[str] = set()
    for source in sources:
        if source in out:
            continue
        base = re.sub(r"[^A-Za-z0-9_]", "_", str(source).rsplit("/", 1)[-1].rsplit(".", 1)[0])
        base = base if base and not base[0].isdigit() else f"m_{base}"
        stem, k = f"{base}{suffix}", 2
        while stem in used:
            stem, k = f"{base}_{k}{suffix}", k + 1
        used.add(stem)
        out[source] = stem
    return out


def build_monitor_modules(compiled: Sequence[Compiled], errors: list | None = None) -> dict[str, MonitorModule]:
    """One :class:`MonitorModule` per requirement file, keyed by the file
    (``RequirementEntry.source``), in input order; requirements keep their order within a
    file. Module names come from :func:`file_stems` (``r1.fret`` -> ``r1_monitors``).
    Internal errors (:class:`InvalidMonitorError`) are appended to ``errors``, the
    requirements concerned being listed in ``SKIPPED`` (see :func:`build_monitor_module`).
    Each requirement's automata are built once (and shared through the disk cache by
    requirements of the same shape)."""
    groups = by_source(compiled)
    stems = file_stems(groups, "_monitors")
    return {source: build_monitor_module(items, stems[source], errors)
            for source, items in groups.items()}


def emit_monitors(compiled: Sequence[Compiled], errors: list | None = None) -> dict[str, str]:
    """The texts of :func:`build_monitor_modules`: ``{module name: source text}`` in input
    order (``r1.fret`` -> ``r1_monitors``); ``errors`` as there."""
    return {m.name: m.text for m in build_monitor_modules(compiled, errors).values()}
