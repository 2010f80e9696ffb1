"""The validation suite's checks of the code fretc generates to run on the robot (T3 uses):
the Python monitors' LTL3 status against Spot's language emptiness, generated code that ids
and texts cannot inject into, the shield's C form against its Python form built with the
strict flags, and ``--prove``'s answers; each against a reference independent of the code
checked (Spot, the C compiler, the Python form the ``shield-python`` check holds).
"""

from __future__ import annotations

import csv
import io
import math
import os
import random
import subprocess
import types
from typing import Any

from fretc.qualification import reference as ref
from fretc.qualification.checks import (SEED, Check, CheckSkipped, Run, _capped,
                                        compiled_keys, traces)
from fretc.qualification.checks_audit import fretc
from fretc.qualification.checks_forms import (C_TIMEOUT, _compiler, _folder, _load,
                                              shield_command)

#: every how many keys the LTL3 check takes one (Spot's emptiness per prefix is the cost)
LTL3_STRIDE = 6
#: random traces per key of the LTL3 check
LTL3_TRACES = 3
#: the strict flags ``--emit c`` promises its code builds with (docs/guide/robot-monitors.md)
STRICT = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror")


def _prefix(trace: list[dict[str, bool]]) -> str:
    """The LTL formula of the runs starting with ``trace``: each tick's letter, nested in X."""
    text = "1"
    for tick in reversed(trace):
        letter = " & ".join(v if tick[v] else f"!{v}" for v in ref.VARIABLES)
        text = f"({letter}) & X({text})"
    return text


def check_ltl3_status(run: Run) -> list[str]:
    """A sample of the 288 keys (every :data:`LTL3_STRIDE`-th) as generated Python monitors,
    stepped over random traces: after each tick the monitor's ``status`` is ``violated``
    exactly when no infinite continuation of the prefix satisfies ft_inf, ``satisfied``
    when none violates it (Spot's emptiness of ft_inf, or its negation, with the prefix),
    else ``unknown`` (Bauer, Leucker and Schallhart, TOSEM 2011)."""
    try:
        import spot
    except ImportError as exc:
        raise CheckSkipped(f"Spot is not installed ({exc})") from None
    from fretc.compiler.codegen import render_module
    from fretc.compiler.printers import to_spot
    from fretc.compiler.semantics import formalize
    from fretc.fretish import parse

    keys = dict(ref.key_sentences())
    comps = compiled_keys(run)[::LTL3_STRIDE]
    module = types.ModuleType("qualify_ltl3")
    exec(compile(render_module([c for _, c in comps], "qualify_ltl3"),  # noqa: S102
                 "<qualify_ltl3>", "exec"), module.__dict__)
    rnd = random.Random(SEED + 5)
    out: list[str] = []
    for key, c in comps:
        phi = spot.formula(to_spot(formalize(parse(keys[key])).ft_inf))
        for _ in range(LTL3_TRACES):
            trace = ref.random_trace(rnd, rnd.randint(1, ref.DURATION + 4))
            monitor = module.MONITORS[c.id]()
            for n in range(1, len(trace) + 1):
                monitor.step(dict(trace[n - 1]))
                prefix = spot.formula(_prefix(trace[:n]))
                bad = spot.translate(spot.formula.And([phi, prefix])).is_empty()
                good = spot.translate(spot.formula.And([spot.formula.Not(phi), prefix])
                                      ).is_empty()
                want = "violated" if bad else "satisfied" if good else "unknown"
                if monitor.status != want:
                    out.append(f"{key} after {n} tick(s) of {trace}: status "
                               f"{monitor.status}, Spot says {want}")
                    break
            if len(out) >= 5:
                return out
    return out


#: an id made to end the generated code's strings, docstrings, comments and lines (a
#: docstring pasted as it is would run the ``raise`` when the module loads)
HOSTILE_ID = 'H"""\nraise SystemExit("injected")\n"""\'*/??/\\\u00c4'
#: a text whose variable names are no identifier of Python or C
HOSTILE_TEXT = 'the sw shall always satisfy "we?ird */ var" & "x??/" | r'


def check_escaping(run: Run) -> list[str]:
    """A requirement whose id holds the quotes, docstring and comment ends, a trigraph,
    backslashes, a line break and non-ASCII, and whose variable names are no identifiers,
    compiled to a Python monitor module (``--emit monitor``'s) and to C (``--emit c``'s):
    the module loads and runs nothing of the id, knows the requirement by its id and judges
    it; the C builds with the strict flags and its runner prints the id escaped (``\\xNN``)."""
    from fretc.compiler.build import compile_entry
    from fretc.compiler.c_codegen import emit_c
    from fretc.compiler.codegen import render_module
    from fretc.qualification.checks import _entry

    compiled = [compile_entry(_entry(HOSTILE_ID, HOSTILE_TEXT))]
    out: list[str] = []
    module = types.ModuleType("qualify_hostile")
    try:
        exec(compile(render_module(compiled, "qualify_hostile"),  # noqa: S102
                     "<qualify_hostile>", "exec"), module.__dict__)
    except (SystemExit, SyntaxError) as exc:
        return [f"the Python module of a hostile id does not load: {type(exc).__name__}: {exc}"]
    monitors = getattr(module, "MONITORS", {})
    if list(monitors) != [HOSTILE_ID]:
        return [f"the Python module's requirements are {list(monitors)!r}, expected the id"]
    monitor = monitors[HOSTILE_ID]()
    monitor.step({"we?ird */ var": True, "x??/": False, "r": False})
    if monitor.finish():
        out.append("the hostile requirement's monitor holds on a violating tick")
    compiler = _compiler()
    folder = _folder(run, "escaping")
    files, skipped = emit_c(compiled)
    if skipped:
        return out + [f"--emit c left the requirement out: {skipped}"]
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    env = dict(os.environ, TMPDIR=str(folder))
    sources = sorted(str(folder / n) for n in files if n.endswith(".c"))
    built = subprocess.run([compiler, *STRICT, "-o", str(folder / "runner"), *sources, "-lm"],
                           capture_output=True, text=True, env=env, timeout=C_TIMEOUT)
    if built.returncode != 0:
        return out + [f"the C of a hostile id does not build: {built.stderr.strip()[-300:]}"]
    (folder / "t.csv").write_text("a\ntrue\n",
                                  encoding="utf-8")
    ran = subprocess.run([str(folder / "runner"), str(folder / "t.csv")], capture_output=True,
                         timeout=C_TIMEOUT, env=env)
    first = ran.stdout.decode("utf-8", "replace").split("\t")[0]
    shown = first.encode("utf-8").decode("unicode_escape").encode("latin-1").decode("utf-8")
    if shown != HOSTILE_ID or "\n" in first or "no column we?ird */ var" not in \
            ran.stdout.decode("utf-8", "replace"):
        out.append(f"the C runner prints the id as {first!r}, expected it escaped with the "
                   "missing column named")
    return out


def _cell(x: Any) -> str:
    """A CSV cell of the C runner: ``true``/``false`` or a double's repr."""
    return ("true" if x else "false") if isinstance(x, bool) else repr(float(x))


def check_shield_c(run: Run) -> list[str]:
    """The ``shield-python`` check's shield as C (``fretc shield --emit c``), built with the
    strict flags, its runner fed random runs (NaN and infinities among the inputs): at every
    tick its output, ``overridden`` and reasons are the Python form's."""
    compiler = _compiler()
    folder = _folder(run, "shield-c")
    code, text = fretc(run, [*shield_command(folder), "--emit", "python", "--emit", "c",
                             "-o", str(folder / "out")])
    if code != 0:
        return [f"fretc shield exited {code}: {text.strip()[-300:]}"]
    gen = folder / "out"
    env = dict(os.environ, TMPDIR=str(folder))
    built = subprocess.run([compiler, *STRICT, "-o", str(folder / "run"),
                            str(gen / "s_shield.c"), str(gen / "s_shield_run.c"), "-lm"],
                           capture_output=True, text=True, env=env, timeout=C_TIMEOUT)
    if built.returncode != 0:
        return [f"the C shield does not build with {' '.join(STRICT)}: "
                f"{built.stderr.strip()[-300:]}"]
    shield_class = _load(gen / "s_shield.py").Shield
    rnd = random.Random(SEED + 6)
    out: list[str] = []
    for n in range(20):
        rows = [(rnd.choice([math.nan, math.inf, -math.inf, 0.0, 9.0, 5.0, 6.0]),
                 rnd.random() < 0.4) for _ in range(rnd.randint(1, 12))]
        stdin = "x,o\n" + "".join(f"{_cell(x)},{_cell(o)}\n" for x, o in rows)
        ran = subprocess.run([str(folder / "run")], input=stdin, capture_output=True,
                             text=True, env=env, timeout=C_TIMEOUT)
        if ran.returncode != 0:
            return [f"run {n}: the C runner exited {ran.returncode}: {ran.stderr[-200:]}"]
        got = list(csv.DictReader(io.StringIO(ran.stdout)))
        shield = shield_class()
        for k, ((x, o), c) in enumerate(zip(rows, got, strict=False)):
            d = shield.step({"x": x}, {"o": o})
            want = (str(int(bool(d.outputs["o"]))), str(int(d.overridden)), set(d.reasons))
            have = (c.get("o"), c.get("overridden"),
                    set(filter(None, (c.get("reasons") or "").split("|"))))
            if want != have:
                out.append(f"run {n} tick {k} (x={x}, proposal o={o}): C {have}, Python {want}")
                break
        if len(got) != len(rows):
            out.append(f"run {n}: {len(got)} rows from the C runner for {len(rows)} ticks")
    return out[:5]


#: an environment no run keeps (the proof must call it vacuous, never proved)
IMPOSSIBLE = "A1: environment shall always satisfy x > 5 & x <= 5\n"


def check_prove(run: Run) -> list[str]:
    """``fretc shield --prove``: the ``shield-python`` check's shield proved on its closed
    loop (each requirement ``holds``, exit 0); under an assumption no run keeps, each is
    ``vacuous`` and the run says NOT PROVED with exit 1, never holds."""
    folder = _folder(run, "prove")
    (folder / "a.fret").write_text(IMPOSSIBLE, encoding="utf-8")
    base = [*shield_command(folder), "--prove", "--emit", "python"]
    out = []
    code, text = fretc(run, [*base, "-o", str(folder / "plain")])
    if code != 0 or "S1: holds" not in text or "S2: holds" not in text:
        out.append(f"the shield's proof: exit {code}, expected 0 with S1 and S2 holding: "
                   f"{text.strip()[-300:]}")
    code, text = fretc(run, [*base, "--assume", str(folder / "a.fret"), "-o",
                             str(folder / "assumed")])
    if code != 1 or "NOT PROVED" not in text or "S1: vacuous" not in text \
            or "holds" in text.replace("S1: vacuous", ""):
        out.append(f"under an impossible assumption: exit {code}, expected 1, S1 vacuous and "
                   f"NOT PROVED: {text.strip()[-300:]}")
    return out


#: C2PO's mission time in the R2U2 check (the suite's traces are shorter)
C2PO_MISSION = 12
#: traces of the suite the R2U2 check runs (one engine run per batch and trace)
C2PO_TRACES = 12


def check_c2po_r2u2(run: Run) -> list[str]:
    """The 288 keys' ``--emit c2po`` text through R2U2 itself (the build of
    ``tools/r2u2/build.sh``; skipped without it): C2PO accepts every entry, and for those
    without ``S`` or ``T`` (R2U2's engine computes them wrongly at the pinned commit) R2U2's
    verdict at each tick of the suite's traces is FRET's finite-trace verdict of the prefix
    ending there (the reference evaluator)."""
    from fretc.qualification import r2u2

    tool = r2u2.locate()
    if tool is None:
        raise CheckSkipped(r2u2.NOT_BUILT)
    folder = _folder(run, "c2po-r2u2")
    keys = {f"K{i:03d}": key for i, (key, _text) in enumerate(ref.key_sentences())}
    fret = folder / "keys.fret"
    fret.write_text("".join(f"{rid}: {text}\n" for rid, (_k, text)
                            in zip(keys, ref.key_sentences())), encoding="utf-8")
    code, text = fretc(run, ["compile", str(fret), "--emit", "c2po", "-o",
                             str(folder / "keys.c2po")])
    if code != 0:
        return [f"--emit c2po: exit {code}: {text.strip()[-300:]}"]
    spec = r2u2.read_spec((folder / "keys.c2po").read_text(encoding="utf-8"))
    compared = [x for x in spec.entries if not spec.since_or_trigger(x)]
    try:
        r2u2.type_check(tool, spec, [x for x in spec.entries if x not in compared],
                        C2PO_MISSION, folder / "accepted")
        batches = r2u2.compile_batches(tool, spec, C2PO_MISSION, folder / "compared",
                                       compared)
    except r2u2.R2U2Error as exc:
        return [f"C2PO refused fretc's specification: {str(exc)[-400:]}"]
    if sorted(spec.entries) != sorted(keys) or not compared:
        return [f"--emit c2po wrote {len(spec.entries)} entries ({len(compared)} without S "
                f"or T) for the {len(keys)} keys"]
    return _capped(_r2u2_verdicts(run, tool, spec, batches, keys, folder))


def _r2u2_verdicts(run: Run, tool: Any, spec: Any, batches: list, keys: dict[str, str],
                   folder: Any) -> list[str]:
    """R2U2's verdicts (the compiled ``batches`` of ``spec``) on the suite's first
    :data:`C2PO_TRACES` traces against the reference at each tick: the failures."""
    from fretc.qualification import r2u2

    out = []
    for n, trace in enumerate(traces(run)[:C2PO_TRACES]):
        csv_path = folder / f"trace{n}.csv"
        r2u2.write_trace(csv_path, spec, trace)
        want = {rid: [ref.verdict(key, trace[:i + 1]) != "violated"
                      for i in range(len(trace))] for rid, key in keys.items()}
        for binary, ids in batches:
            try:
                streams = r2u2.run(tool, binary, csv_path)
                got = {ids[i]: r2u2.per_tick(s, len(trace)) for i, s in streams.items()}
            except r2u2.R2U2Error as exc:
                out.append(f"R2U2 on trace {n}: {str(exc)[-300:]}")
                continue
            if sorted(got) != sorted(ids.values()):
                out.append(f"R2U2 gave no verdict of {sorted(set(ids.values()) - set(got))}")
            out += [f"{keys[rid]} on trace {n}: R2U2 {v}, expected {want[rid]}"
                    for rid, v in sorted(got.items()) if v != want[rid]]
    return out


#: the checks of the generated code that runs on the robot, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("monitors-ltl3", ("TOR-GEN-002", "TOR-VER-009"),
          "the Python monitors' LTL3 status against Spot's emptiness", check_ltl3_status),
    Check("generated-escaping", ("TOR-GEN-005",),
          "ids and texts cannot inject into the generated code", check_escaping),
    Check("shield-c", ("TOR-SHD-004",),
          "the shield's C form, strict flags, against its Python form", check_shield_c),
    Check("shield-prove", ("TOR-SHD-002",),
          "--prove proves the closed loop, never an impossible assumption", check_prove),
    Check("c2po-r2u2", ("TOR-GEN-006",),
          "--emit c2po through C2PO and R2U2 against the reference", check_c2po_r2u2),
)
