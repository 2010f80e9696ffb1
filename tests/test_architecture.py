"""The house stays walkable: packages in the pipeline's order and subpackages that import only
what their docstrings say, a generous backstop on module and function sizes (one job per
module is checked in review), and R1's way from text to verdict as ARCHITECTURE.md states it,
measured by tracing a real run (tests/trace_main_line.py)."""

from __future__ import annotations

import ast
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: ARCHITECTURE.md, "R1 from text to verdict": the most moves and data forms R1's way may have
#: (13 moves since the cached requirements are decoded by fretc's own JSON decoder, not by
#: pickle, which ran whatever code the cache folder held)
MAX_MOVES = 13
MAX_FORMS = 10
#: a backstop, not a target (ARCHITECTURE.md, "One job per module"): a module holds one job
#: and is split by job when it grows; no docstring or comment is ever shortened to fit these
MAX_MODULE_LINES = 900
MAX_FUNCTION_LINES = 80


def _python_files() -> list[Path]:
    out = subprocess.run(["git", "ls-files", "*.py"], cwd=REPO, capture_output=True,
                         text=True)
    if out.returncode != 0:  # not a git checkout (an unpacked archive): every file
        return sorted(p for p in REPO.rglob("*.py") if ".venv" not in p.parts)
    return [REPO / f for f in out.stdout.split() if (REPO / f).exists()]


def oversized(files: list[Path], root: Path = REPO) -> list[str]:
    """``path: N lines`` for modules over :data:`MAX_MODULE_LINES` and ``path:line name: N
    lines`` for functions over :data:`MAX_FUNCTION_LINES` (paths relative to ``root``)."""
    out = []
    for p in files:
        text = p.read_text(encoding="utf-8")
        where = p.relative_to(root)
        n = len(text.splitlines())
        if n > MAX_MODULE_LINES:
            out.append(f"{where}: {n} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                if length > MAX_FUNCTION_LINES:
                    out.append(f"{where}:{node.lineno} {node.name}: {length} lines")
    return out


def test_modules_and_functions_within_limits():
    assert oversized(_python_files()) == []


def test_the_size_check_finds_a_long_function_and_module(tmp_path):
    p = tmp_path / "long.py"
    p.write_text("def f():\n" + "    x = 1\n" * MAX_FUNCTION_LINES
                 + "y = 2\n" * MAX_MODULE_LINES)
    assert oversized([p], tmp_path) == [f"long.py: {MAX_MODULE_LINES + MAX_FUNCTION_LINES + 1} "
                                        "lines", f"long.py:1 f: {MAX_FUNCTION_LINES + 1} lines"]


@pytest.mark.skipif(not (REPO / "traces" / "nominal.mcap").exists(),
                    reason="traces/nominal.mcap is absent")
def test_r1_main_line_within_the_limits():
    from trace_main_line import describe, trace

    line = trace("R1")
    report = "\n".join(describe(line))
    assert line.moves and "Verdict" in line.forms, report
    assert len(line.moves) <= MAX_MOVES, report
    assert len(line.forms) <= MAX_FORMS, report


#: ARCHITECTURE.md, "Packages in the pipeline's order": a package imports only packages before
#: it (lazy imports inside functions included). ``fretc.signals.bindings`` (the binding
#: language) sits below the rest of ``fretc.signals`` (sampling), which uses it; ``fretc.cli``
#: (the commands) and the package's own ``__init__``/``__main__`` come last.
PACKAGE_ORDER = ("fretc.common", "fretc.fretish", "fretc.compiler", "fretc.logs",
                 "fretc.signals.bindings", "fretc.signals", "fretc.monitors", "fretc.check",
                 "fretc.audit", "fretc.testing", "fretc.shield", "fretc.live", "fretc.sim",
                 "fretc.reports", "fretc.editor", "fretc.qualification", "fretc.cli", "fretc")
#: the repository's source folders: each installs as ``fretc.<folder>`` (src/fretc/ links each
#: of them); ``src/fretc/`` itself is ``fretc``, holding ``fretc.cli``
LIBRARY = ("common", "fretish", "compiler", "logs", "signals", "monitors", "check", "audit",
           "testing", "shield", "live", "sim", "reports", "editor", "qualification", "src/fretc")
#: the packages whose modules may import ``fretc.reports``: the reports and the front ends
FRONT_ENDS = ("fretc.reports", "fretc.editor", "fretc.qualification", "fretc.cli", "fretc")


def source_files(folder: Path) -> list[Path]:
    """The ``*.py`` files under ``folder``, sorted, not following links to folders (src/fretc
    links the pipeline's folders, which are listed on their own)."""
    import os

    out = []
    for here, dirs, files in os.walk(folder, followlinks=False):
        dirs[:] = sorted(d for d in dirs if not (Path(here) / d).is_symlink())
        out += [Path(here) / f for f in files if f.endswith(".py")]
    return sorted(out)


def installed_name(path: Path, root: Path = REPO) -> str:
    """The import name of the source file ``path`` once installed: ``audit/log.py`` ->
    ``fretc.audit.log``, ``src/fretc/cli/audit.py`` -> ``fretc.cli.audit``."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[:2] == ["src", "fretc"]:
        parts = parts[1:]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts if parts[0] == "fretc" else ["fretc"] + parts)


def layer(module: str) -> int | None:
    """Rank in :data:`PACKAGE_ORDER` of the package holding ``module`` (the longest listed
    prefix), None outside the listed packages."""
    best = None
    for rank, pkg in enumerate(PACKAGE_ORDER):
        if module == pkg or module.startswith(pkg + "."):
            if best is None or len(pkg) > len(PACKAGE_ORDER[best]):
                best = rank
    return best


def back_arrows(graph: dict[str, set[str]]) -> list[str]:
    """``a -> b`` for every import (at any depth of the module, lazy ones included) from a
    package to one after it in :data:`PACKAGE_ORDER`, and from anything but the front ends
    (:data:`FRONT_ENDS`: the commands, the language server) into ``fretc.reports`` (the
    reports read the audit's model; only the front ends call them)."""
    out = []
    for mod, targets in sorted(graph.items()):
        rank = layer(mod)
        if rank is None:
            continue
        for t in sorted(targets):
            trank = layer(t)
            if trank is None:
                continue
            into_reports = (PACKAGE_ORDER[trank] == "fretc.reports"
                            and PACKAGE_ORDER[rank] not in FRONT_ENDS)
            if trank > rank or into_reports:
                out.append(f"{mod} -> {t}")
    return out


def test_packages_import_in_pipeline_order():
    from test_layering import import_graph

    assert back_arrows(import_graph()) == []


#: ARCHITECTURE.md, "Subpackages": inside a layer, the subpackages that hold one capability
#: each (a log format family, a transport, the per-entity audit ...) and the modules of the
#: layer they must not import (each subpackage's docstring says what it may import): the
#: log formats and the transports are siblings that share only their layer's top modules
#: (an MCAP file's ROS 2 channels are CDR: ``fretc.logs.mcap`` may read ``fretc.logs.ros``)
SUBPACKAGE_LIMITS = {
    "fretc.logs.mcap": ("fretc.logs.flight", "fretc.logs.csv"),
    "fretc.logs.ros": ("fretc.logs.mcap", "fretc.logs.flight", "fretc.logs.csv"),
    "fretc.logs.flight": ("fretc.logs.mcap", "fretc.logs.ros", "fretc.logs.csv"),
    "fretc.logs.csv": ("fretc.logs.mcap", "fretc.logs.ros", "fretc.logs.flight"),
    "fretc.live.websocket": ("fretc.live.dds", "fretc.live.zenoh", "fretc.live.watch"),
    "fretc.live.dds": ("fretc.live.websocket", "fretc.live.zenoh", "fretc.live.watch"),
    "fretc.live.zenoh": ("fretc.live.websocket", "fretc.live.dds", "fretc.live.watch"),
    "fretc.audit.entities": ("fretc.audit.sampled", "fretc.audit.fleet"),
    "fretc.audit.sampled": ("fretc.audit.fleet",),
}


def crossings(graph: dict[str, set[str]]) -> list[str]:
    """``a -> b`` for every import (lazy and type-only ones included) from a module of a
    subpackage of :data:`SUBPACKAGE_LIMITS` into a module it must not import."""
    out = []
    for mod, targets in sorted(graph.items()):
        for sub, banned in SUBPACKAGE_LIMITS.items():
            if mod == sub or mod.startswith(sub + "."):
                out += [f"{mod} -> {t}" for t in sorted(targets)
                        if any(t == b or t.startswith(b + ".") for b in banned)]
    return out


def test_subpackages_import_what_their_docstrings_say():
    from test_layering import import_graph

    assert crossings(import_graph()) == []
    # every subpackage of the layers says what it holds and what it may import
    inits = [p for pkg in LIBRARY for p in source_files(REPO / pkg)
             if p.name == "__init__.py" and len(p.relative_to(REPO).parts) == 3
             and p.relative_to(REPO).parts[0] != "src"]
    assert inits, "no subpackage found"
    silent = [str(p.relative_to(REPO)) for p in inits
              if "May import" not in (ast.get_docstring(ast.parse(p.read_text())) or "")]
    assert silent == []


def test_a_crossing_between_subpackages_is_found(tmp_path):
    from test_layering import _imports

    p = tmp_path / "x.py"
    p.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                 "    from fretc.logs.flight.ulog import UlogSource\n")
    known = {"fretc.logs.csv.x", "fretc.logs.flight.ulog", "fretc.logs.base"}
    assert crossings({"fretc.logs.csv.x": _imports("fretc.logs.csv.x", p, known)}) == [
        "fretc.logs.csv.x -> fretc.logs.flight.ulog"]


def test_a_back_arrow_is_found(tmp_path):
    # the check itself: a lazy import inside a function of logs/ into audit/ is a back arrow,
    # and so is sim/ reading reports/
    from test_layering import _imports

    p = tmp_path / "x.py"
    p.write_text("def f():\n    from fretc.audit.verdict import Verdict\n")
    known = {"fretc.logs.x", "fretc.audit.verdict", "fretc.reports.terminal", "fretc.sim.y"}
    graph = {"fretc.logs.x": _imports("fretc.logs.x", p, known)}
    q = tmp_path / "y.py"
    q.write_text("from fretc.reports.terminal import robustness_text\n")
    graph["fretc.sim.y"] = _imports("fretc.sim.y", q, known)
    assert back_arrows(graph) == ["fretc.logs.x -> fretc.audit.verdict",
                                  "fretc.sim.y -> fretc.reports.terminal"]


def undocumented(files: list[Path], root: Path = REPO) -> list[str]:
    """``path:line name`` of every public function, class and method without a docstring."""
    out = []
    for p in files:
        tree = ast.parse(p.read_text(encoding="utf-8"))
        defs = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
        nodes = [(n, n.name) for n in tree.body if isinstance(n, defs)]
        nodes += [(s, f"{n.name}.{s.name}") for n in tree.body if isinstance(n, ast.ClassDef)
                  and not n.name.startswith("_") for s in n.body if isinstance(s, defs)]
        for node, name in nodes:
            if not node.name.startswith("_") and not ast.get_docstring(node):
                out.append(f"{p.relative_to(root)}:{node.lineno} {name}")
    return out


def test_public_functions_and_classes_have_docstrings(tmp_path):
    files = [p for p in _python_files()
             if any(p.relative_to(REPO).as_posix().startswith(f + "/") for f in LIBRARY)]
    assert undocumented(files) == []
    bare = tmp_path / "bare.py"
    bare.write_text("def f():\n    pass\n\n\nclass C:\n    def g(self):\n        pass\n")
    assert undocumented([bare], tmp_path) == ["bare.py:1 f", "bare.py:5 C", "bare.py:6 C.g"]


def unannotated(files: list[Path], root: Path = REPO) -> list[str]:
    """``path:line name: what`` for every public function and method (the functions and
    methods :func:`undocumented` checks, in modules whose name does not start with ``_`` but
    ``__init__`` and ``__main__``) whose parameters (``self`` and ``cls`` aside) or return type
    are not annotated; ``what`` lists the bare parameters, then ``return``."""
    out = []
    for p in files:
        if p.name.startswith("_") and p.stem not in ("__init__", "__main__"):
            continue
        tree = ast.parse(p.read_text(encoding="utf-8"))
        defs = (ast.FunctionDef, ast.AsyncFunctionDef)
        nodes = [(n, n.name, False) for n in tree.body if isinstance(n, defs)]
        nodes += [(s, f"{n.name}.{s.name}", True) for n in tree.body
                  if isinstance(n, ast.ClassDef) and not n.name.startswith("_")
                  for s in n.body if isinstance(s, defs)]
        for node, name, method in nodes:
            if node.name.startswith("_"):
                continue
            a = node.args
            params = [*a.posonlyargs, *a.args, *a.kwonlyargs, *filter(None, (a.vararg, a.kwarg))]
            static = any(isinstance(d, ast.Name) and d.id == "staticmethod"
                         for d in node.decorator_list)
            if method and not static and params and params[0] in (a.posonlyargs + a.args)[:1]:
                params = params[1:]  # self, cls
            bare = [x.arg for x in params if x.annotation is None]
            bare += ["return"] if node.returns is None else []
            if bare:
                out.append(f"{p.relative_to(root)}:{node.lineno} {name}: {', '.join(bare)}")
    return out


def test_public_functions_are_annotated(tmp_path):
    # mypy checks the bodies of annotated functions only, and readers of the package rely on
    # its public signatures: every public parameter and return type is annotated
    files = [p for p in _python_files()
             if any(p.relative_to(REPO).as_posix().startswith(f + "/") for f in LIBRARY)]
    assert unannotated(files) == []
    bare = tmp_path / "bare.py"
    bare.write_text("def f(a, b: int, *c):\n    pass\n\n\ndef _g(x):\n    pass\n\n\n"
                    "class C:\n    def m(self, y: int):\n        pass\n\n"
                    "    @staticmethod\n    def s(z) -> None:\n        pass\n")
    (tmp_path / "_private.py").write_text("def f(x):\n    pass\n")
    assert unannotated([bare, tmp_path / "_private.py"], tmp_path) == [
        "bare.py:1 f: a, c, return", "bare.py:10 C.m: return", "bare.py:14 C.s: z"]
