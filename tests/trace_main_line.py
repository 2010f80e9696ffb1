"""R1's way from text to verdict, measured by tracing a real run (``sys.setprofile``).

Usage::

    python tests/trace_main_line.py [REQUIREMENT_ID]   # default R1, on traces/nominal.mcap

runs ``fretc audit -r requirements/r1.fret traces/nominal.mcap`` in this process and prints

* the run's whole module graph: the project modules it calls into and the distinct
  module-to-module call edges (calls made while modules are imported are left out);
* **R1's main line**: every *move*, a call from one project module into a function of another
  whose arguments or return value carry one of R1's objects, and the *data forms* (the
  classes of R1's objects) that cross module boundaries in those moves. Constructors and
  property getters are not moves (they make or read an object; its class is counted where
  the object crosses a boundary).

An object is one of R1's when it is an instance of a class defined in the project and names
R1 (its ``id`` or ``requirement`` is ``"R1"``, or its ``entry``, ``compiled`` or
``requirement`` attribute is one of R1's), or when one of R1's objects holds it in an
attribute (the parsed requirement, its formalization, ...). Containers (lists, tuples,
dicts, sets) are looked into one level, so a list of requirement plans that holds R1's
carries R1. Moves are counted once per (caller module, callee module) pair.

ARCHITECTURE.md quotes these counts; ``tests/test_architecture.py`` fails when they grow past
the limits there.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("common", "fretish", "compiler", "check", "logs", "signals", "monitors", "audit",
            "live", "sim", "reports", "fretc")
#: attributes through which an object is found to be one of the requirement's
_OWNER_ATTRS = ("entry", "compiled", "requirement")
_CONTAINERS = (list, tuple, set, frozenset)
#: making an object of another module's class is not a move (its data form is counted where
#: it crosses a module boundary)
_CONSTRUCTORS = ("__init__", "__new__", "__post_init__")


def _project_module(name: str | None) -> str | None:
    if name and name.split(".")[0] in PACKAGES:
        return name
    return None


@dataclass
class MainLine:
    """What :func:`trace` found: the run's module graph and the requirement's main line.

    Attributes:
        modules: project modules called into during the run.
        edges: distinct (caller module, callee module) pairs of the run.
        moves: (caller module, callee module) -> the first function called and the data forms
            of the requirement that crossed, in the order first seen.
        forms: the data forms (class names) of the requirement's objects seen in moves.
    """

    modules: set[str] = field(default_factory=set)
    edges: set[tuple[str, str]] = field(default_factory=set)
    moves: dict[tuple[str, str], tuple[str, list[str]]] = field(default_factory=dict)
    forms: list[str] = field(default_factory=list)


class _Tracer:
    """The profile function: every cross-module call of the run with the project objects in
    its arguments and return value (kept alive, so their ids stay unique); the requirement's
    objects are found at the end (:meth:`finish`), when all of them exist."""

    def __init__(self) -> None:
        self.out = MainLine()
        self.calls: list[tuple[str, str, str, list]] = []
        self.stack: list[tuple[str, str, str, list] | None] = []

    def __call__(self, frame, event, arg):
        if event == "call":
            self.stack.append(self._enter(frame))
        elif event == "return" and self.stack:
            entry = self.stack.pop()
            if entry is not None:
                entry[3].extend(_objects([arg]))
                self.calls.append(entry)

    def _enter(self, frame) -> tuple[str, str, str, list] | None:
        callee = _project_module(frame.f_globals.get("__name__"))
        back = frame.f_back
        caller = _project_module(back.f_globals.get("__name__")) if back else None
        name = frame.f_code.co_name
        if (callee is None or caller is None or caller == callee or name.startswith("<")
                or name in _CONSTRUCTORS or _is_property(frame) or _importing(back)):
            return None
        self.out.modules.update((caller, callee))
        self.out.edges.add((caller, callee))
        code = frame.f_code
        args = [frame.f_locals.get(a) for a in
                code.co_varnames[:code.co_argcount + code.co_kwonlyargcount]]
        return caller, callee, name, _objects(args)

    def finish(self, rid: str) -> MainLine:
        """The moves and data forms of ``rid``'s objects."""
        mine = _owned_by(rid, [x for call in self.calls for x in call[3]])
        for caller, callee, name, objs in self.calls:
            forms = [type(x).__name__ for x in objs if id(x) in mine]
            if not forms:
                continue
            _, seen = self.out.moves.setdefault((caller, callee), (name, []))
            for f in forms:
                if f not in seen:
                    seen.append(f)
                if f not in self.out.forms:
                    self.out.forms.append(f)
        return self.out


def _is_project_object(x) -> bool:
    return (not isinstance(x, type)
            and _project_module(getattr(type(x), "__module__", None)) is not None)


def _objects(values) -> list:
    """The project objects among ``values``, looking one level into containers."""
    out = []
    for v in values:
        items = (list(v.values()) if isinstance(v, dict)
                 else list(v) if isinstance(v, _CONTAINERS) else [v])
        out.extend(x for x in items[:64] if _is_project_object(x))
    return out


def _is_property(frame) -> bool:
    """The frame runs a property's getter (an attribute read, not a move)."""
    self = frame.f_locals.get("self")
    return self is not None and isinstance(getattr(type(self), frame.f_code.co_name, None),
                                           property)


def _attr(x, name):
    try:
        return getattr(x, name, None)
    except Exception:  # a property that fails on a half-built object
        return None


def _owned_by(rid: str, objects: list) -> set[int]:
    """Ids of the requirement's objects among ``objects``: those naming it, those holding one
    of them (``entry``, ``compiled``, ``requirement``), and those they hold, to a fixpoint."""
    by_id = {id(x): x for x in objects}
    mine = {i for i, x in by_id.items() if rid in (_attr(x, "id"), _attr(x, "requirement"))}
    while True:
        grown = set(mine)
        for i, x in by_id.items():
            if i not in grown and any(id(_attr(x, a)) in mine for a in _OWNER_ATTRS):
                grown.add(i)
        for i in list(grown):
            for a in _OWNER_ATTRS + ("formalization", "ast"):
                y = _attr(by_id[i], a)
                if y is not None and id(y) in by_id:
                    grown.add(id(y))
        if grown == mine:
            return mine
        mine = grown


def _importing(frame) -> bool:
    """The frame runs inside an import (importlib's machinery is on the stack)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def trace(rid: str = "R1", requirements: str = "requirements/r1.fret",
          log: str = "traces/nominal.mcap") -> MainLine:
    """Run ``fretc audit -r REQUIREMENTS LOG --no-progress`` in this process under
    ``sys.setprofile`` and return the run's module graph and ``rid``'s main line. The run
    traced is a user's second one: the same command runs once before, untraced, so that
    fretc's disk cache holds what the first run computes (parsed requirements, monitor
    code, automata) and the count is the same whatever ran before. The run's own output is
    discarded; its exit code must be 0 or 1 (raises ``RuntimeError`` otherwise)."""
    from click.testing import CliRunner

    from fretc.cli import main

    tracer = _Tracer()
    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        runner = CliRunner()
        runner.invoke(main, ["audit", "-r", requirements, log, "--no-progress"])  # (warm)
        sys.setprofile(tracer)
        try:
            res = runner.invoke(main, ["audit", "-r", requirements, log, "--no-progress"])
        finally:
            sys.setprofile(None)
    finally:
        os.chdir(cwd)
    if res.exit_code not in (0, 1):
        raise RuntimeError(f"fretc audit exited {res.exit_code}: {res.output[-400:]}")
    return tracer.finish(rid)


def describe(line: MainLine, rid: str = "R1") -> Iterator[str]:
    """The report :func:`trace`'s result prints, one line at a time."""
    yield (f"the run: {len(line.modules)} project modules, {len(line.edges)} module-to-module "
           "call edges")
    yield f"{rid}'s main line: {len(line.moves)} moves, {len(line.forms)} data forms"
    for (caller, callee), (name, forms) in line.moves.items():
        yield f"  {caller} -> {callee}.{name}: {', '.join(forms)}"
    yield "data forms: " + ", ".join(line.forms)


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    rid = sys.argv[1] if len(sys.argv) > 1 else "R1"
    for text in describe(trace(rid), rid):
        print(text)
