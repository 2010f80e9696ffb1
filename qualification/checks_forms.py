"""The validation suite's checks of the forms fretc generates for the robot and for AJPF:
the C99 monitors built with the machine's C compiler and run on CSV traces, a shield's Python
form stepped over random runs with unreadable inputs, and AJPF properties; each held against
:mod:`fretc.qualification.reference` or against the text the documentation gives.

A check that needs what the machine lacks (a C compiler) raises :class:`CheckSkipped`: the
report says so, and the requirements it would show stay ``not checked here``.
"""

from __future__ import annotations

import importlib.util
import math
import os
import random
import shutil
import subprocess
from pathlib import Path
from typing import Any

from fretc.qualification import reference as ref
from fretc.qualification.checks import SEED, Check, CheckSkipped, Run
from fretc.qualification.checks_audit import E2E_TRACES, _csv, fretc

#: seconds a C build or run may take before the check fails
C_TIMEOUT = 300


def _folder(run: Run, name: str) -> Path:
    """A new folder ``name`` in the run's work folder (a link or a file there refused)."""
    from fretc.common.outputs import sub_folder

    return Path(sub_folder(run.work, name))


def _compiler() -> str:
    """The C compiler on the PATH (``cc``, else ``gcc``, else ``clang``). Raises
    :class:`CheckSkipped` when there is none."""
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return found
    raise CheckSkipped("no C compiler (cc, gcc or clang) on the PATH")


def check_c_monitors(run: Run) -> list[str]:
    """The 288 key sentences as C99 monitors (``fretc FILE --emit c``), built with the
    machine's C compiler (``-std=c99``, its temporary files in the work folder), their runner
    run on random CSV traces: each verdict word is the reference's."""
    compiler = _compiler()
    folder = _folder(run, "c-monitors")
    keys = ref.key_sentences()
    req = folder / "keys.fret"
    req.write_text("".join(f"K{i:03d}: {s}\n" for i, (_, s) in enumerate(keys)), "utf-8")
    code, text = fretc(run, [str(req), "--emit", "c", "-o", str(folder / "c")])
    if code != 0:
        return [f"fretc --emit c exited {code}: {text.strip()[-300:]}"]
    sources = sorted(str(p) for p in (folder / "c").glob("*.c"))
    env = dict(os.environ, TMPDIR=str(folder))
    built = subprocess.run([compiler, "-std=c99", "-O0", "-o", str(folder / "runner"),
                            *sources, "-lm"], capture_output=True, text=True, env=env,
                           timeout=C_TIMEOUT)
    if built.returncode != 0:
        return [f"the C monitors do not build: {built.stderr.strip()[-300:]}"]
    rnd = random.Random(SEED + 2)
    out = []
    for j in range(E2E_TRACES):
        trace = ref.random_trace(rnd, rnd.randint(1, ref.DURATION + 7))
        csv = folder / f"t{j:02d}.csv"
        csv.write_text(_csv({v: [t[v] for t in trace] for v in ref.VARIABLES}), "utf-8")
        ran = subprocess.run([str(folder / "runner"), str(csv)], capture_output=True,
                             text=True, env=env, timeout=C_TIMEOUT)
        got = dict(line.split("\t")[:2] for line in ran.stdout.splitlines() if "\t" in line)
        for i, (key, _) in enumerate(keys):
            want = ref.verdict(key, trace)
            if got.get(f"K{i:03d}") != want:
                out.append(f"{key} on {csv.name}: the C runner says {got.get(f'K{i:03d}')}, "
                           f"expected {want}")
    return out[:5] + ([f"... and {len(out) - 5} more"] if len(out) > 5 else [])


#: the shield check's requirements: inputs ``x`` (a number), outputs ``o`` (a boolean); in
#: the reference's words, ``c`` is ``x > 5`` and ``r`` is ``o``
SHIELD_REQUIREMENTS = ("S1: whenever x > 5 ctrl shall immediately satisfy o\n"
                       f"S2: upon x > 5 ctrl shall for {ref.DURATION} ticks satisfy o\n")
SHIELD_KEYS = {"S1": "null,holding,immediately", "S2": "null,regular,for"}
SHIELD_RUNS = 40


def shield_command(folder: Path, o_binding: str = "/o.data") -> list[str]:
    """Write :data:`SHIELD_REQUIREMENTS` and their bindings (``x`` the Float64 of /x, ``o``
    bound to ``o_binding``, 100 ms ticks) into ``folder``; returns the ``fretc shield``
    arguments that read them (``--inputs x --outputs o``), without emits or output."""
    (folder / "s.fret").write_text(SHIELD_REQUIREMENTS, encoding="utf-8")
    (folder / "s.toml").write_text('[tick]\nperiod = "100 ms"\n\n[variables]\n'
                                   f'x = "/x.data"\no = "{o_binding}"\n', encoding="utf-8")
    return ["shield", str(folder / "s.fret"), "-b", str(folder / "s.toml"), "--inputs", "x",
            "--outputs", "o"]


def _load(path: Path) -> Any:
    """The Python module at ``path``, loaded under a name of its own."""
    spec = importlib.util.spec_from_file_location(f"qualify_{path.stem}", path)
    assert spec is not None and spec.loader is not None  # (a .py file's spec has a loader)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _shield_runs(shield_class: Any) -> list[str]:
    """Step fresh shields over random runs (``x`` a number or NaN, proposals random) and
    hold the closed loop against the reference: both requirements hold whatever value an
    unread ``x`` had (each unread tick read both ways), and a proposal ``o = true``, which
    breaks neither, is never changed."""
    rnd = random.Random(SEED + 3)
    out: list[str] = []
    for n in range(SHIELD_RUNS):
        shield, ticks = shield_class(), []
        for _ in range(rnd.randint(1, 9)):
            x = math.nan if rnd.random() < 0.15 else float(rnd.randint(0, 9))
            proposed = rnd.random() < 0.3
            d = shield.step({"x": x}, {"o": proposed})
            if proposed and d.overridden:
                out.append(f"run {n}: the safe proposal o = true was changed")
            ticks.append((x, bool(d.outputs["o"])))
        for unread_as in (False, True):
            trace = [{"m": False, "s": False, "r": o,
                      "c": unread_as if math.isnan(x) else x > 5} for x, o in ticks]
            for rid, key in SHIELD_KEYS.items():
                if ref.verdict(key, trace) == "violated":
                    out.append(f"run {n}: {rid} violated on the shielded run {ticks} "
                               f"(unread x read as {'> 5' if unread_as else '<= 5'})")
    return out[:5]


def check_shield(run: Run) -> list[str]:
    """A shield synthesized from two requirements (``fretc shield --emit python``), its
    Python form loaded and stepped over random runs (:func:`_shield_runs`)."""
    folder = _folder(run, "shield")
    code, text = fretc(run, [*shield_command(folder), "--emit", "python", "-o",
                             str(folder / "out")])
    forms = sorted((folder / "out").glob("*_shield.py"))
    if code != 0 or len(forms) != 1:
        return [f"fretc shield exited {code} with {len(forms)} Python forms: "
                f"{text.strip()[-300:]}"]
    return _shield_runs(_load(forms[0]).Shield)


#: (requirement, the AJPF property fretc must write for it, or None: refused with a reason)
PSL_CASES = (
    ("R1: the sw shall always satisfy r", "R1: [] B(sw,r)"),
    ("R2: whenever c the sw shall eventually satisfy r & !s",
     "R2: [] (B(sw,c) -> <> (B(sw,r) & ~B(sw,s)))"),
    ("R3: whenever c the sw shall always satisfy r | s",
     "R3: [] (B(sw,c) -> [] (B(sw,r) || B(sw,s)))"),
    ("R4: the sw shall at the next timepoint satisfy r", None),
)


def check_psl(run: Run) -> list[str]:
    """``--emit psl`` writes each requirement's ft_inf in AJPF's property language, every
    binary sub-formula parenthesized, and refuses with its reason what AJPF cannot state."""
    folder = _folder(run, "psl")
    (folder / "p.fret").write_text("".join(f"{t}\n" for t, _ in PSL_CASES), encoding="utf-8")
    code, text = fretc(run, [str(folder / "p.fret"), "--emit", "psl"])
    lines = text.splitlines()
    out = [] if code == 0 else [f"exit {code}: {text.strip()[-200:]}"]
    for req, want in PSL_CASES:
        rid = req.split(":")[0]
        if want is not None and want not in lines:
            out.append(f"{rid}: expected {want!r}")
        if want is None and (any(line.startswith(f"{rid}:") for line in lines)
                             or "no AJPF property" not in text):
            out.append(f"{rid}: not refused with a reason")
    return out


#: the generated forms' checks, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("monitors-c", ("TOR-GEN-003",),
          "C99 monitors of the 288 keys, built here, against the reference", check_c_monitors),
    Check("shield-python", ("TOR-SHD-001", "TOR-SHD-003"),
          "a shield's Python form over random runs with unreadable inputs", check_shield),
    Check("ajpf-psl", ("TOR-GEN-004",), "AJPF properties and refusals", check_psl),
)
