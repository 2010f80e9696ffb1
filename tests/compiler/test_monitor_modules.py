"""The compiler -> audit contract: :func:`fretc.compiler.codegen.build_monitor_modules`
returns, per requirement file, the module text ``--emit monitor`` writes and, per
requirement, its class name, template input and LTL3 automata, built once."""

from __future__ import annotations

import random
import types

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fretc.compiler import codegen
from fretc.compiler.automata import Automaton, LTL3Automata
from fretc.compiler.build import compile_entries
from fretc.fretish.files import RequirementEntry
from fretc.fretish.parser import parse

FILES = {
    "a/r.fret": [("R1", "whenever p the sw shall within 3 ticks satisfy q"),
                 ("R2", "the sw shall always satisfy persists(2, p)"),  # future pt: skipped
                 ("R3", "in m upon c the sw shall eventually satisfy x > 2")],
    "b/r.fret": [("R1", "the sw shall always satisfy p"),  # same id, another file
                 ("S1", "after m the sw shall never satisfy p & q")],
    "c.fret": [("T1", "upon p the sw shall within 40 ticks satisfy q")],  # progression
}


def compiled_files():
    entries = [RequirementEntry(id=rid, text=text, source=src, line=i + 1, column=1,
                                requirement=parse(text))
               for src, reqs in FILES.items() for i, (rid, text) in enumerate(reqs)]
    return compile_entries(entries)


def load(mm):
    mod = types.ModuleType(mm.name)
    exec(compile(mm.text, mm.name, "exec"), mod.__dict__)
    return mod


def test_modules_pair_requirements_with_classes_and_automata(monkeypatch):
    calls = []
    real = codegen.ltl3_automata

    def counting(ft_inf):
        calls.append(ft_inf)
        return real(ft_inf)

    monkeypatch.setattr(codegen, "ltl3_automata", counting)
    compiled = compiled_files()
    modules = codegen.build_monitor_modules(compiled)
    assert list(modules) == list(FILES)  # keyed by file, in input order
    assert [m.name for m in modules.values()] == ["r_monitors", "r_2_monitors", "c_monitors"]
    assert len(calls) == 5  # once per monitored requirement, never for the skipped one
    assert {m.name: m.text for m in modules.values()} == codegen.emit_monitors(compiled)
    for _src, mm in modules.items():
        mod = load(mm)
        assert list(mm.monitors) == list(mod.MONITORS)
        assert mm.skipped == mod.SKIPPED
        for rid, info in mm.monitors.items():
            assert mod.MONITORS[rid].__name__ == info.class_name == info.source.class_name
            assert info.automata is info.source.automata
            assert isinstance(info.automata, LTL3Automata)
    assert list(modules["a/r.fret"].skipped) == ["R2"]
    assert "future" in modules["a/r.fret"].skipped["R2"]
    assert "progression" in modules["c.fret"].monitors["T1"].automata.note


def replay(aut: Automaton, letters) -> int | None:
    """The index of the letter at which ``aut`` rejects (-1: before any), or None."""
    if aut.empty:
        return -1
    state = aut.initial
    for i, letter in enumerate(letters):
        state = aut.table[state][letter]
        if state < 0:
            return i
    return None


_MODULES = codegen.build_monitor_modules(compiled_files())


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2 ** 32), st.integers(1, 30))
def test_public_automata_give_the_modules_status(seed, n):
    """Replaying :class:`Automaton` tables as documented (letter bit i = atoms[i]) gives the
    generated monitor's status and status tick."""
    rnd = random.Random(seed)
    trace = [{"p": rnd.random() < 0.5, "q": rnd.random() < 0.3, "m": rnd.random() < 0.7,
              "c": rnd.random() < 0.5, "x": rnd.randint(0, 4)} for _ in range(n)]
    for mm in _MODULES.values():
        mod = load(mm)
        for rid, info in mm.monitors.items():
            mon = mod.MONITORS[rid]()
            for sample in trace:
                mon.step({v: sample[v] for v in mon.VARIABLES})
            best = ("unknown", None)
            for aut, outcome in ((info.automata.bad, "violated"),
                                 (info.automata.good, "satisfied")):
                if aut is None:
                    continue
                letters = [sum(1 << j for j, a in enumerate(aut.atoms) if _truth(a, s))
                           for s in trace]
                hit = replay(aut, letters)
                if hit == -1:
                    best = (outcome, None)
                    break
                if hit is not None and (best[1] is None or hit < best[1]):
                    best = (outcome, hit)
            assert (mon.status, mon.status_tick) == best, (rid, trace)


def _truth(atom, sample) -> bool:
    if atom.op == "ap":
        return bool(sample[atom.name])
    assert atom.op == "cmp" and atom.name == ">", atom  # x > 2 is the only comparison
    return sample[atom.args[0].name] > int(atom.args[1].name)


# --------------------------------------------------------------------------- shared shapes
#: Requirements of one shape (same code but for the variable names; D1 and D2 even share
#: their names) and one of another shape, in one module.
SHAPED = [(f"S{i}", f"in m{i} upon p{i} the sw shall within 3 ticks satisfy q{i}")
          for i in range(6)] + [
    ("D1", "in m0 upon p0 the sw shall within 3 ticks satisfy q0"),
    ("D2", "in m0 upon p0 the sw shall within 3 ticks satisfy q0"),
    ("O1", "whenever p1 the sw shall immediately satisfy q0"),
]


def _shaped_modules():
    entries = [RequirementEntry(id=rid, text=text, source="shaped.fret", line=i + 1,
                                column=1, requirement=parse(text))
               for i, (rid, text) in enumerate(SHAPED)]
    compiled = compile_entries(entries)
    together = load(codegen.build_monitor_module(compiled, "together"))
    alone = {c.id: load(codegen.build_monitor_module([c], "alone")) for c in compiled}
    return together, alone


_SHAPED = []


def shaped_modules():
    if not _SHAPED:
        _SHAPED.append(_shaped_modules())
    return _SHAPED[0]


def _run(monitor, trace):
    out = [(monitor.step(s), monitor.status, monitor.status_tick) for s in trace]
    return out, monitor.finish()


def test_requirements_of_one_shape_share_code_but_not_state():
    together, _ = shaped_modules()
    classes = [together.MONITORS[rid] for rid, _ in SHAPED]
    # the six S* and D* requirements share one shape (and its tables), O1 has its own
    assert len(together._SHAPES) == 2
    assert len({c._SHAPE for c in classes[:-1]}) == 1
    _monitors = [c() for c in classes]
    assert classes[0]._BAD is classes[1]._BAD is not None  # read-only, shared
    assert classes[0].step is not classes[1].step  # each class reads its own variables
    assert [c.VARIABLES for c in classes[:2]] == [["m0", "p0", "q0"], ["m1", "p1", "q1"]]


@settings(max_examples=25, deadline=None)
@given(st.lists(st.lists(st.booleans(), min_size=18, max_size=18), min_size=1, max_size=40),
       st.randoms(use_true_random=False))
def test_each_requirement_of_a_shared_shape_has_its_own_verdict(rows, rnd):
    """Stepped side by side on one trace, each monitor of a module where many requirements
    share a shape gives, tick by tick, the pt verdict, LTL3 status and final verdict of a
    module generated for that requirement alone; two objects of one class stepped on two
    traces do not disturb each other."""
    together, alone = shaped_modules()
    names = [f"{v}{i}" for i in range(6) for v in "mpq"]
    trace = [dict(zip(names, row)) for row in rows]
    other = [dict(zip(names, rnd.sample(row, len(row)))) for row in rows]
    side_by_side = {rid: together.MONITORS[rid]() for rid, _ in SHAPED}
    twin = together.MONITORS["S0"]()  # a second object of one class, another trace
    got = {rid: [] for rid in side_by_side}
    got_twin = []
    for s, o in zip(trace, other):
        for rid, m in side_by_side.items():
            got[rid].append((m.step(s), m.status, m.status_tick))
        got_twin.append((twin.step(o), twin.status, twin.status_tick))
    for rid, m in side_by_side.items():
        assert (got[rid], m.finish()) == _run(alone[rid].MONITORS[rid](), trace), rid
    assert (got_twin, twin.finish()) == _run(alone["S0"].MONITORS["S0"](), other)


def test_a_requirements_monitor_source_is_found_by_its_class_name():
    """What the report shows as a requirement's generated monitor: its ``_monitor`` call
    (id, text, formulas, variables) and the shape entry with its step code."""
    from fretc.reports.trace import _class_source

    entries = [RequirementEntry(id=rid, text=text, source="shaped.fret", line=i + 1,
                                column=1, requirement=parse(text))
               for i, (rid, text) in enumerate(SHAPED)]
    mm = codegen.build_monitor_module(compile_entries(entries), "shaped")
    info = mm.monitors["O1"]
    src = _class_source(mm.text, info.class_name)
    assert src.startswith(f"{info.class_name} = _monitor(") and "ID='O1'" in src
    for text in (info.source.text, info.source.ft, info.source.ft_inf, info.source.pt):
        assert repr(text) in src
    assert f"VARIABLES={info.source.variables!r}" in src
    shape = src[src.index("# _SHAPES["):]
    assert "def step(self, sample):" in shape and "S0" not in src


def _names_by_dis(code):
    """The reference of ``codegen._names``: the standard library's instruction decoding."""
    import dis

    defined, reads, stack = set(), set(), [code]
    while stack:
        co = stack.pop()
        for ins in dis.get_instructions(co):
            if ins.opname in ("LOAD_GLOBAL", "LOAD_NAME"):
                reads.add(ins.argval)
            elif co is code and ins.opname in ("STORE_NAME", "STORE_GLOBAL", "IMPORT_NAME"):
                defined.add(ins.argval)
        stack.extend(c for c in co.co_consts if isinstance(c, types.CodeType))
    return defined, reads


@settings(max_examples=40, deadline=None)
@given(st.lists(st.sampled_from(["load", "store", "attr", "call", "global"]), max_size=12),
       st.integers(0, 600), st.randoms(use_true_random=False))
def test_names_of_code_agree_with_dis(kinds, n_filler, rnd):
    """``codegen._names`` (which decodes bytecode itself, for speed) reads the same defined
    and read names as ``dis``, at the top level and in nested functions, also past 256
    names (``EXTENDED_ARG`` prefixes)."""
    pool = [f"x{i}" for i in range(12)]
    lines = [f"f{i} = {i}" for i in range(n_filler)]  # many names: EXTENDED_ARG past 255
    body = []
    for k in kinds:
        a, b = rnd.choice(pool), rnd.choice(pool)
        if k == "load":
            lines.append(f"y = {a}")
            body.append(f"z = {b}")
        elif k == "store":
            lines.append(f"{a} = 1")
        elif k == "attr":
            body.append(f"z = {a}.{b}")
        elif k == "call":
            body.append(f"{a}({b}, f{n_filler - 1 if n_filler else 0})")
        else:
            lines.append(f"def h{len(lines)}():\n    global {a}\n    {a} = {b}")
    lines.append("def g():\n    " + "\n    ".join(body or ["pass"]))
    lines.append("import math as " + rnd.choice(pool))
    code = compile("\n".join(lines), "<t>", "exec")
    assert codegen._names(code) == _names_by_dis(code)
    mm = codegen.build_monitor_module(compiled_files()[:3], "m")
    mod_code = compile(mm.text, "m", "exec")
    assert codegen._names(mod_code) == _names_by_dis(mod_code)


@pytest.mark.tor("TOR-GEN-001")
def test_a_file_of_300_requirements_keeps_every_monitor_and_its_verdicts():
    """A requirement file large enough that its module's code has more than 256 names (its
    name operations then carry an ``EXTENDED_ARG`` prefix, which the load check decodes)
    gets a monitor for every requirement, none skipped, each ending with its verdict."""
    texts = [(f"R{i}", f"the sw shall always satisfy v{i} > {i}") for i in range(300)]
    entries = [RequirementEntry(id=rid, text=text, source="big.fret", line=i + 1, column=1,
                                requirement=parse(text))
               for i, (rid, text) in enumerate(texts)]
    errors: list = []
    mm = codegen.build_monitor_module(compile_entries(entries), "big", errors)
    assert len(compile(mm.text, "big", "exec").co_names) > 256
    mod = load(mm)
    assert not errors and mod.SKIPPED == {} and list(mod.MONITORS) == [r for r, _ in texts]
    for k, second, holds in ((0, 1, True), (150, 150, False), (299, 300, True)):
        mon = mod.MONITORS[f"R{k}"]()
        mon.step({f"v{k}": k + 1})
        mon.step({f"v{k}": second})
        assert bool(mon.finish()) is holds
