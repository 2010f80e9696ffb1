"""R2U2 itself, run on fretc's C2PO output: the build of ``tools/r2u2/build.sh`` located
(:func:`locate`), C2PO run on ``fretc --emit c2po``'s text, R2U2's C engine run on a CSV trace,
and its verdict stream read back as one verdict per formula per tick; for ``fretc qualify``
(TOR-GEN-006), the tests and ``bench/bench_r2u2.py``.

Facts of R2U2 used here, all of the commit ``tools/r2u2/build.sh`` pins (its
``monitors/c/docs/user/output.md``, ``src/cli/csv_trace.c``, ``src/lib.c``,
``src/internals/bounds.h`` and ``compiler/docs/user/commands.md``):

* the verdict stream: a line ``id:t,T`` or ``id:t,F`` per result, ``id`` the formula's number
  (C2PO's ``F label id`` line of the assembly), ``t`` the last tick of a run of ticks with the
  same verdict, starting after the formula's previous ``t``. Past-time results may name
  ticks beyond the row just read (``O[0,9] p`` true now is true for nine more ticks) and
  beyond the trace's end, which are not ticks of the run;
* the trace: a CSV with a ``#`` header line (skipped), one row a tick, columns in the order of
  C2PO's signal map; with the Booleanizer a value with a decimal point is read as a float,
  one without as an integer (so floats are written with a point, Booleans as ``0``/``1``);
* the engine's bounds (signals, nodes, temporal operators, SCQ slots ...) are fixed when it is
  built; a binary over them makes the engine print nothing and exit 0, so the specifications
  are compiled in batches that C2PO's ``write_bounds_c`` says fit, and every tick of every
  formula must have a verdict;
* the engine's ``S`` and ``T`` (:data:`SINCE_DEFECT`) are not MLTL's at this commit.

Every failure of C2PO or of the engine raises :class:`R2U2Error`.
"""

from __future__ import annotations

import os
import re
import subprocess
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["R2U2Error", "R2U2", "NOT_BUILT", "build_folder", "locate", "Spec", "read_spec",
           "write_trace", "compile_batches", "type_check", "run", "per_tick", "SCQ_CONSTANT"]

#: why R2U2's checks are skipped when ``tools/r2u2/build.sh`` has not been run
NOT_BUILT = "R2U2 not built: run tools/r2u2/build.sh"


class R2U2Error(RuntimeError):
    """C2PO refused a specification, the engine failed, or its output is not the stream
    this module reads (the message holds what they printed)."""


def _need(ok: bool, what: object) -> None:
    """Raise :class:`R2U2Error` with ``what`` unless ``ok``."""
    if not ok:
        raise R2U2Error(str(what))

#: bounds of R2U2's ``bounds.h`` that C2PO's ``write_bounds_c`` states for a specification
#: (the auxiliary-string ones serve an engine feature the release build leaves off)
_CHECKED = ("R2U2_MAX_SIGNALS", "R2U2_MAX_ATOMICS", "R2U2_MAX_BZ_INSTRUCTIONS",
            "R2U2_MAX_TL_INSTRUCTIONS", "R2U2_MAX_TEMPORAL_OPERATORS", "R2U2_MAX_QUEUE_SLOTS")
#: one more slot in every SCQ than C2PO computes (C2PO's ``--scq-constant``): with C2PO's own
#: sizes a formula such as ``(H[0,M] a) -> (H[0,M] ((H[0,M] b) -> c))`` gets wrong verdicts
#: from the engine (a queue too short at this commit); one slot more, they are MLTL's
SCQ_CONSTANT = 1
_DEFINE = re.compile(r"^#define (R2U2_MAX_\w+) (\d+)\s*$", re.M)


@dataclass(frozen=True)
class R2U2:
    """A finished R2U2 build: the C engine, C2PO's script and Python, the commit, and the
    engine's compiled-in bounds (``{name: value}`` of its ``bounds.h``)."""

    engine: Path
    c2po: Path
    python: Path
    commit: str
    limits: dict


def build_folder() -> Path:
    """Where ``tools/r2u2/build.sh`` builds: ``$FRETC_TOOLS/r2u2``, FRETC_TOOLS defaulting to
    ``~/.cache/fretc/tools``."""
    tools = os.environ.get("FRETC_TOOLS") or str(Path.home() / ".cache" / "fretc" / "tools")
    return Path(tools) / "r2u2"


def locate() -> R2U2 | None:
    """The R2U2 build named by ``r2u2.env`` in :func:`build_folder` (written last by the build
    script), or None when it is absent or one of its files is missing."""
    env = build_folder() / "r2u2.env"
    if not env.is_file():
        return None
    kv = dict(line.split("=", 1) for line in env.read_text().splitlines() if "=" in line)
    paths = [Path(kv.get(k, "")) for k in ("R2U2_ENGINE", "C2PO_SCRIPT", "C2PO_PYTHON")]
    if not all(p.is_file() for p in paths):
        return None
    bounds = paths[0].parents[1] / "src" / "internals" / "bounds.h"
    limits = {k: int(v) for k, v in _DEFINE.findall(bounds.read_text())}
    return R2U2(paths[0], paths[1], paths[2], kv.get("R2U2_COMMIT", ""), limits)


@dataclass
class Spec:
    """fretc's C2PO text cut apart: the ``INPUT`` signals (``[(symbol, kind)]`` in order),
    each ``PTSPEC`` entry (``{label: its two lines}``) and the FRET variable of each signal
    (``{symbol: FRET name}``, the symbol itself when fretc kept the name)."""

    head: str
    signals: list
    entries: dict
    fret_names: dict

    def batch(self, labels: Iterable[str]) -> str:
        """A C2PO text with every signal and the entries of ``labels``."""
        return self.head + "\nPTSPEC\n" + "".join(self.entries[x] for x in labels)

    def since_or_trigger(self, label: str) -> bool:
        """Whether the entry's formula has ``S`` or ``T`` (see :data:`SINCE_DEFECT`)."""
        return re.search(r" [ST]\[", self.entries[label].split("\n")[1]) is not None


def read_spec(text: str) -> Spec:
    """:class:`Spec` of a C2PO text that ``fretc --emit c2po`` wrote (one file)."""
    head, _, body = text.partition("\nPTSPEC\n")
    signals = []
    for names, kind in re.findall(r"^    (.*): (bool|float);$", head, flags=re.M):
        signals += [(s.strip(), kind) for s in names.split(",")]
    entries = {m.group(1): m.group(0) for m in re.finditer(
        r"^    -- .*\n    (\w+): .*;\n", body, flags=re.M)}
    renamed = dict(re.findall(r"^-- signal (\w+): FRET variable (.*)$", head, flags=re.M))
    return Spec(head, signals, entries, {s: renamed.get(s, s) for s, _ in signals})


def write_trace(path: Path, spec: Spec, states: list) -> None:
    """The CSV trace of ``states`` (FRET variable -> value) for R2U2: a ``#`` header of the
    signals in :attr:`Spec.signals` order (that of the map), Booleans ``0``/``1``, numbers as
    floats with a decimal point."""
    rows = ["# " + ",".join(s for s, _ in spec.signals)]
    for state in states:
        cells = []
        for sym, kind in spec.signals:
            v = state[spec.fret_names[sym]]
            text = str(int(bool(v))) if kind == "bool" else repr(float(v))
            _need(kind == "bool" or "." in text, text)
            cells.append(text)
        rows.append(",".join(cells))
    path.write_text("\n".join(rows) + "\n")


def compile_batches(tool: R2U2, spec: Spec, mission_time: int, folder: Path,
                    labels: Iterable[str] | None = None, size: int = 8) -> list:
    """C2PO's binaries of the entries ``labels`` of ``spec`` (default: all), at most
    ``size`` entries a binary and each within the engine's bounds (a batch over them is split
    in two and compiled again): ``[(binary path, {formula id: label})]``. All batches are
    compiled by one C2PO process (a script of C2PO commands: ``enable_booleanizer``,
    ``set_mission_time``, then per batch ``parse_c2po``, ``parse_map`` and ``compile``, C2PO's
    default passes, with :data:`SCQ_CONSTANT`). R2U2Error if C2PO refuses any."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "signals.map").write_text(
        "".join(f"{s}:{i}\n" for i, (s, _) in enumerate(spec.signals)))
    labels = list(spec.entries) if labels is None else list(labels)
    todo = [labels[i:i + size] for i in range(0, len(labels), size)]
    done: list = []
    while todo:
        built = _c2po(tool, spec, todo, mission_time, folder, len(done))
        todo = []
        for group, (binary, ids, bounds) in built:
            over = [k for k in _CHECKED if bounds[k] > tool.limits[k]]
            if not over:
                _need(sorted(ids.values()) == sorted(group), (group, ids))
                done.append((binary, ids))
            else:
                _need(len(group) > 1, f"{group[0]} alone is over R2U2's bounds: {over}")
                todo += [group[:len(group) // 2], group[len(group) // 2:]]
    return done


def _c2po(tool: R2U2, spec: Spec, groups: list, mission_time: int, folder: Path,
          start: int) -> list:
    lines = ["enable_booleanizer", f"set_mission_time {mission_time}"]
    files = []
    for k, group in enumerate(groups, start):
        stem = folder / f"batch{k}"
        (stem.with_suffix(".c2po")).write_text(spec.batch(group))
        lines += [f"parse_c2po {stem}.c2po", f"parse_map {folder / 'signals.map'}",
                  f"compile --scq-constant {SCQ_CONSTANT} --assembly-filename {stem}.asm {stem}.bin",
                  f"write_bounds_c {stem}.h"]
        files.append(stem)
    script = folder / f"script{start}.txt"
    script.write_text("\n".join(lines) + "\n")
    res = subprocess.run([str(tool.python), str(tool.c2po), "--script", str(script)],
                         capture_output=True, text=True, timeout=900)
    _need(res.returncode == 0, res.stdout + res.stderr)
    out = []
    for group, stem in zip(groups, files):
        ids = {int(i): label for label, i in re.findall(
            r"^F (\w+) (\d+)$", stem.with_suffix(".asm").read_text(), flags=re.M)}
        bounds = {k: int(v) for k, v in _DEFINE.findall(stem.with_suffix(".h").read_text())}
        out.append((group, (stem.with_suffix(".bin"), ids, bounds)))
    return out


def type_check(tool: R2U2, spec: Spec, labels: Sequence[str], mission_time: int,
               folder: Path) -> None:
    """C2PO parses and type-checks the entries ``labels`` of ``spec`` (one file, C2PO's
    ``parse_c2po``, ``parse_map`` and ``type_check``); R2U2Error with C2PO's messages if
    it refuses any."""
    if not labels:
        return
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "signals.map").write_text(
        "".join(f"{s}:{i}\n" for i, (s, _) in enumerate(spec.signals)))
    (folder / "all.c2po").write_text(spec.batch(labels))
    script = folder / "check.txt"
    script.write_text(f"enable_booleanizer\nset_mission_time {mission_time}\nparse_c2po {folder / 'all.c2po'}\n"
                      f"parse_map {folder / 'signals.map'}\ntype_check\n")
    res = subprocess.run([str(tool.python), str(tool.c2po), "--script", str(script)],
                         capture_output=True, text=True, timeout=900)
    _need(res.returncode == 0 and "error" not in res.stdout + res.stderr,
          res.stdout + res.stderr)


def run(tool: R2U2, binary: Path, trace: Path) -> dict:
    """R2U2's verdict stream on ``trace``: ``{formula id: [(t, verdict), ...]}`` in the order
    the engine wrote them. R2U2Error if the engine fails."""
    res = subprocess.run([str(tool.engine), str(binary), str(trace)], capture_output=True,
                         text=True, timeout=120)
    _need(res.returncode == 0, res.stdout + res.stderr)
    out: dict = {}
    for line in res.stdout.splitlines():
        m = re.fullmatch(r"(\d+):(\d+),([TF])", line)
        if m is None:
            raise R2U2Error(f"not a verdict of the engine's stream: {line!r}")
        out.setdefault(int(m.group(1)), []).append((int(m.group(2)), m.group(3) == "T"))
    return out


def per_tick(stream: list, ticks: int) -> list:
    """The verdict at each tick ``0 .. ticks-1`` of one formula's results (``[(t, verdict)]``:
    each the verdict of the ticks after the previous ``t`` up to ``t``). R2U2Error if
    the ``t`` do not increase or a tick has no verdict."""
    out: list = []
    last = -1
    for t, v in stream:
        _need(t > last, stream)
        out += [v] * (min(t, ticks - 1) - last) if last < ticks - 1 else []
        last = t
    _need(len(out) == ticks, (len(out), ticks, stream))
    return out
