"""Structure of the code: no import cycles between modules (lazy and type-only imports
included), and ``fretc FILE --emit
ltl`` starts without the heavy libraries (Spot, Jinja2, numpy, mcap, Ray) that only code
generation, checking and the audit need."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
from test_architecture import LIBRARY as PACKAGES, installed_name, source_files  # noqa: E402


def _modules() -> dict[str, Path]:
    """Installed module name -> source file, for every module of every source folder."""
    return {installed_name(p): p for pkg in PACKAGES for p in source_files(REPO / pkg)}


def _type_only(tree: ast.Module) -> set[int]:
    """``id``s of the import statements under ``if TYPE_CHECKING:`` (for the type checker
    alone: they never run)."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and ast.unparse(node.test) in ("TYPE_CHECKING",
                                                                    "typing.TYPE_CHECKING"):
            out.update(id(n) for s in node.body for n in ast.walk(s)
                       if isinstance(n, (ast.Import, ast.ImportFrom)))
    return out


def _imports(name: str, path: Path, known, type_only: bool = True) -> set[str]:
    """Modules of ``known`` that ``name`` imports anywhere (inside functions too; with
    ``type_only``, under ``if TYPE_CHECKING:`` too)."""
    pkg = name if path.stem == "__init__" else name.rsplit(".", 1)[0]
    out = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = set() if type_only else _type_only(tree)
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: level 1 is this package, 2 its parent ...
                anchor = pkg.split(".")[:len(pkg.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            for alias in node.names:
                target = f"{base}.{alias.name}"
                out.add(target if target in known else base)
        elif isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
    return {m for m in out if m in known and m != name}


def import_graph(type_only: bool = True) -> dict[str, set[str]]:
    """Module -> the project modules it imports (anywhere in it; with ``type_only``, for the
    type checker alone too), for every source module."""
    mods = _modules()
    return {m: _imports(m, p, mods, type_only) for m, p in mods.items()}


def cycles_of(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every import cycle of ``graph`` (module -> the modules it imports), each once: a
    strongly connected component of two or more modules (Tarjan), as a path through it that
    comes back to its first module, smallest module first."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:  # (the graph is a few hundred modules: recursion is fine)
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(_path_through(graph, sorted(comp)))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def _path_through(graph: dict[str, set[str]], comp: list[str]) -> list[str]:
    """A shortest cycle from ``comp[0]`` back to itself inside the component ``comp``."""
    inside = set(comp)
    start = comp[0]
    prev: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph.get(v, ())):
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return path[::-1] + [start]
                if w in inside and w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    return comp + [start]  # (unreachable for a strongly connected component)


def test_no_import_cycles():
    # every import counts: at the top, lazy ones inside functions, and those for the type
    # checker alone (if TYPE_CHECKING:), for two modules that name each other's types are one
    # concept split in two or a type living in the wrong module (ARCHITECTURE.md)
    cycles = cycles_of(import_graph())
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_a_cycle_through_a_lazy_or_type_only_import_is_found(tmp_path):
    a, b, c = tmp_path / "a.py", tmp_path / "b.py", tmp_path / "c.py"
    a.write_text("def f():\n    from fretc.b import g\n")
    b.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from fretc.a import f\n")
    c.write_text("import fretc.a\n")
    known = {"fretc.a", "fretc.b", "fretc.c"}
    graph = {m: _imports(m, p, known) for m, p in (("fretc.a", a), ("fretc.b", b),
                                                   ("fretc.c", c))}
    assert cycles_of(graph) == [["fretc.a", "fretc.b", "fretc.a"]]


def test_type_checking_imports_are_told_apart(tmp_path):
    # _imports can leave out the imports for the type checker alone (start-up checks read
    # what runs); the cycle and layer tests count them
    p = tmp_path / "a.py"
    p.write_text("from typing import TYPE_CHECKING\n\nimport fretc.x\n\n"
                 "if TYPE_CHECKING:\n    from fretc.y import Y\n")
    known = {"fretc.x", "fretc.y"}
    assert _imports("fretc.a", p, known) == {"fretc.x", "fretc.y"}
    assert _imports("fretc.a", p, known, type_only=False) == {"fretc.x"}


def test_emit_ltl_starts_without_heavy_libraries(tmp_path):
    f = tmp_path / "r.fret"
    f.write_text("R1: whenever p the sw shall within 3 ticks satisfy q\n")
    code = ("import sys\n"
            "sys.argv = ['fretc', sys.argv[1], '--emit', 'ltl']\n"
            "from fretc.cli import main\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "heavy = sorted(m for m in sys.modules if m.split('.')[0] in "
            "('spot', 'buddy', 'jinja2', 'numpy', 'mcap', 'ray', 'rosbags'))\n"
            "print('HEAVY', heavy)\n")
    out = subprocess.run([sys.executable, "-c", code, str(f)], cwd=REPO, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "HEAVY []" in out.stdout, out.stdout


def test_an_audit_with_its_automata_cached_loads_no_spot_junit_or_process_pool(tmp_path):
    """``fretc audit`` of one log reads its LTL3 automata, its monitor module's text and its
    parsed requirements and binding expressions from the cache: neither Spot (for its
    version, the cache key), Jinja nor Lark is loaded, nor the JUnit writer without
    ``--junit``, the progress bar off a terminal, the process pool without ``-j`` or the Ray
    fleet without ``--ray`` (start-up of every audit)."""
    code = ("import sys\n"
            "sys.argv = ['fretc', 'audit', '-r', 'requirements', 'traces/stop_delay.mcap',\n"
            "            '--no-progress']\n"
            "from fretc.cli import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "loaded = sorted(m for m in sys.modules if m in ('spot', 'fretc.reports.junit', "
            "'rich.progress', 'multiprocessing', 'concurrent.futures', 'fretc.audit.fleet.ray', "
            "'jinja2', 'lark'))\n"
            "print('LOADED', loaded)\n")
    env = dict(os.environ, FRETC_CACHE_DIR=str(tmp_path / "cache"))
    for _ in range(2):  # the first run fills the cache
        out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                             text=True, timeout=300, env=env)
    assert "LOADED []" in out.stdout, (out.stdout, out.stderr[-2000:])


def test_the_command_starts_numpy_without_blas_threads():
    """fretc makes no BLAS call: the command keeps OpenBLAS to one thread (its threads' start
    is CPU of every command), unless the user set ``OPENBLAS_NUM_THREADS``."""
    if not os.path.isdir("/proc/self/task"):
        import pytest
        pytest.skip("no /proc/self/task to count the threads (not Linux)")
    code = "import os, fretc.cli, numpy; print(len(os.listdir('/proc/self/task')))"
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, env=env, check=True)
    assert out.stdout.strip() == "1", out.stdout
    if (os.cpu_count() or 1) > 1:  # the user's own choice is kept
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             timeout=120, env=dict(env, OPENBLAS_NUM_THREADS="2"), check=True)
        assert out.stdout.strip() == "2", out.stdout


def test_every_package_is_installed():
    # `pip install .` (the README's first command) installs only the packages pyproject.toml
    # lists: a new sub-package missing there breaks the installed fretc, not the tests
    import tomllib

    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {installed_name(p.parent / "__init__.py") for pkg in PACKAGES + ("templates",)
             for p in source_files(REPO / pkg) if p.name == "__init__.py"}
    assert found <= listed, sorted(found - listed)


def test_one_import_rule():
    # every import of fretc's own code, in the sources, tests and benchmarks, is absolute
    # and names ``fretc.``: a bare ``compiler`` or ``audit`` would import another
    # distribution's package of that name once installed (or nothing)
    bare = {name for name in PACKAGES if "/" not in name} | {"templates"}
    found = []
    files = subprocess.run(["git", "ls-files", "*.py"], cwd=REPO, capture_output=True,
                           text=True).stdout.split() or [
        str(p.relative_to(REPO)) for p in REPO.rglob("*.py") if ".venv" not in p.parts]
    for name in files:
        path = REPO / name
        if not path.exists():
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level:
                found.append(f"{name}:{node.lineno} relative import")
            mods = ([node.module or ""] if isinstance(node, ast.ImportFrom) else
                    [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            found += [f"{name}:{node.lineno} {m}" for m in mods if m.split(".")[0] in bare]
    assert found == []
