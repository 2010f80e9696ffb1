"""Helpers of the C monitor tests and benchmarks: the system C compiler (or a skip with the
reason), the generated files built with the strict flags of ``--emit c``, and a driver program that steps
any monitor of a generated unit over traces given on its standard input and prints, per
tick, the pt verdict, the LTL3 verdict and its tick, then FRET's finite-trace verdict and
the audit's word (the C twin of replaying a Python monitor)."""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import pytest

#: the flags of ``fretc --emit c``'s promise (docs/guide/robot-monitors.md)
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
NO_CC = "no C compiler found (cc, gcc or clang on PATH, or $CC): the C monitors are not built"
WORDS = {0: "satisfied", 1: "vacuous", 2: "violated", 3: "unknown", 4: "error"}
LTL3 = {0: "unknown", 1: "satisfied", 2: "violated"}


def c_compiler() -> str | None:
    """The C compiler: $CC, else cc, gcc or clang on PATH; None when there is none."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def needs_cc():
    """The compiler, or skip the calling test with :data:`NO_CC`."""
    cc = c_compiler()
    if cc is None:
        pytest.skip(NO_CC)
    return cc


def write(files: dict[str, str], folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")


def build(folder: Path, sources: list[str], out: str, flags=(), sanitize: bool = True) -> Path:
    """Compile ``sources`` (file names in ``folder``) into ``folder/out`` with
    :data:`STRICT` (+ :data:`SANITIZE`); AssertionError with the compiler's output on any
    diagnostic.

    A build is kept in the suite's cache folder (``FRETC_CACHE_DIR``/cc, tests/conftest.py)
    under a key of the command, the compiler's version and the bytes of every source and
    header of ``folder``: the same generated files are compiled once, then copied (only a
    build without any diagnostic is kept, so the check that they compile warning-free holds
    for each distinct source)."""
    cc = needs_cc()
    cmd = [cc, *STRICT, *(SANITIZE if sanitize else []), *flags, "-o", out, *sources, "-lm"]
    key = hashlib.sha256("\0".join([*cmd, _cc_version(cc)]).encode())
    for name in sorted({*sources, *(p.name for p in folder.glob("*.h"))}):
        key.update(name.encode() + b"\0" + (folder / name).read_bytes() + b"\0")
    root = os.environ.get("FRETC_CACHE_DIR")  # empty: the cache is off
    kept = Path(root) / "cc" / key.hexdigest()[:32] if root else None
    if kept is not None and kept.is_file():
        shutil.copy2(kept, folder / out)
        return folder / out
    got = subprocess.run(cmd, cwd=folder, capture_output=True, text=True)
    assert got.returncode == 0 and not got.stderr.strip(), got.stderr[-4000:]
    if kept is None:
        return folder / out
    kept.parent.mkdir(parents=True, exist_ok=True)
    part = kept.with_name(f"{kept.name}.{os.getpid()}.part")
    shutil.copy2(folder / out, part)
    os.replace(part, kept)  # whole or absent, whatever runs beside it
    return folder / out


@functools.cache
def _cc_version(cc: str) -> str:
    got = subprocess.run([cc, "--version"], capture_output=True, text=True)
    return cc + got.stdout


def driver_source(units) -> str:
    """C source of a driver over the monitors of ``units`` (``c_codegen.CUnit`` list).

    Input: per trace ``K N`` (monitor number in order, ticks), then per tick the input
    fields of monitor K in order (booleans 0/1, numbers as C reads them: nan, inf).
    Output: per tick ``verdict ltl3 ltl3_tick``, then ``F finish verdict unread_tick``."""
    monitors = [m for u in units for m in u.monitors]
    out = [f'#include "{u.stem}.h"' for u in units]
    out += ["#include <stdio.h>", "", "int main(void)", "{", "    int k;", "    long n, t;",
            "    while (scanf(\"%d %ld\", &k, &n) == 2) {", "        switch (k) {"]
    for i, m in enumerate(monitors):
        p = m.prefix
        out += [f"        case {i}: {{", f"            {p}_state s;", f"            {p}_inputs in;",
                "            int b;", "            (void)b;", f"            {p}_init(&s);",
                "            for (t = 0; t < n; t++) {"]
        for x in m.inputs:
            if x.ctype == "bool":
                out += ["                if (scanf(\"%d\", &b) != 1)", "                    return 2;",
                        f"                in.{x.field} = b != 0;"]
            else:
                out += [f"                if (scanf(\"%lf\", &in.{x.field}) != 1)",
                        "                    return 2;"]
        out += [f"                b = (int){p}_step(&s, &in);",
                f"                printf(\"%d %d %lld\\n\", b, (int){p}_ltl3(&s), (long long){p}_ltl3_tick(&s));",
                "            }",
                f"            printf(\"F %d %d %lld\\n\", {p}_finish(&s), (int){p}_verdict(&s), (long long){p}_unread_tick(&s));",
                "            break;", "        }"]
    out += ["        default: return 3;", "        }", "    }", "    return 0;", "}", ""]
    return "\n".join(out)


def value_text(x, ctype: str) -> str:
    if ctype == "bool":
        return "1" if x else "0"
    return repr(float(x))


def run_driver(exe: Path, jobs: list[tuple[int, object, list[dict]]]) -> list[dict]:
    """Run ``exe`` (:func:`driver_source`) over ``jobs`` (monitor number, its CMonitor,
    trace as a list of {FRET name: value}); per job ``{"ticks": [(verdict, ltl3, tick)],
    "finish": int, "verdict": word, "unread": int}``."""
    lines = []
    for k, m, trace in jobs:
        lines.append(f"{k} {len(trace)}")
        for state in trace:
            lines.append(" ".join(value_text(state[_name(x)], x.ctype) for x in m.inputs))
    got = subprocess.run([str(exe)], input="\n".join(lines) + "\n", capture_output=True,
                         text=True)
    assert got.returncode == 0, got.stderr[-4000:]
    rows = got.stdout.splitlines()
    out, i = [], 0
    for _, _, trace in jobs:
        ticks = []
        for _ in trace:
            v, status, tick = rows[i].split()
            ticks.append((v == "1", LTL3[int(status)], None if tick == "-1" else int(tick)))
            i += 1
        _, fin, word, unread = rows[i].split()
        i += 1
        out.append({"ticks": ticks, "finish": int(fin), "verdict": WORDS[int(word)],
                    "unread": int(unread)})
    return out


def _name(x) -> str:
    return x.raw_name
