"""Mutation campaign of the tool operational requirements, one area at a time, with
cosmic-ray (PyPI ``cosmic-ray``, 8.7.0).

The qualification kit asks that, over every area a requirement covers, each requirement's
traced tests kill the mutants of its area. :data:`AREAS` is the table: an area's name, the
source it mutates (``path`` for a whole module, ``path::name`` for one top-level function or
class of it) and the requirements (TOR ids) whose traced tests (their ``tor`` markers, read
by ``tests/tor_matrix.py``) must kill those mutants. For each area asked for:

1. the repository is cloned into ``WORK/<area>`` (``git clone``: the committed tree, never
   the working copy under test), so a mutant never touches this clone;
2. a cosmic-ray configuration is written there: the area's modules, the ``local``
   distributor (one worker), and a test command that runs the traced tests with this
   repository's Python (``--python``, default ``.venv/bin/python``) and
   ``PYTHONPATH=<clone>/src``, so that fretc is imported from the mutated clone (the
   baseline run checks it: the tests must pass there, and ``fretc.__file__`` must lie in the
   clone);
3. the per-mutant timeout is ``--timeout-factor`` (3) times the baseline's wall time;
4. ``cosmic-ray init`` lists the work items (one mutant each) in the session file, an
   sqlite database;
5. the mutants outside the area (a ``path::name`` entry keeps the lines of that definition),
   those inside an annotation of a module that postpones their evaluation (``from
   __future__ import annotations``: equivalent mutants, counted apart) and, with
   ``--sample N``, all but N of the others, chosen by ``random.Random(seed)`` over
   the mutants sorted by file, position, operator and occurrence (cosmic-ray's job ids are
   random: the same mutants on every run of the same tree), are marked
   *skipped* through cosmic-ray's own session interface
   (``WorkDB.set_multiple_results`` with ``WorkerOutcome.SKIPPED``, what cosmic-ray's
   filters such as ``cr-filter-lines`` do): ``cosmic-ray exec`` runs only the work items
   without a result;
6. ``cosmic-ray exec`` runs the rest, and the results are read back from the session
   (``WorkDB.completed_work_items``) into a JSON report: per area the mutants in the area,
   in its annotations, run, killed, survived, timed out, incompetent (the test command could not start, or the
   mutant does not compile) and skipped, each survivor with its file, line, operator and
   diff, and the baseline's time and the command.

Run it with the Python of the environment cosmic-ray is installed in (cosmic-ray is not one
of fretc's dependencies; ``pip install 'fretc[mutation]'`` or a virtual environment of its
own):

    /work/mutvenv/bin/python bench/mutation_campaign.py verdict-words durations c2po \\
        --sample 40 --seed 1 -o reports/mutation.json
    /work/mutvenv/bin/python bench/mutation_campaign.py --list

prints a table of the areas run. A survivor is then judged by hand (an equivalent mutant, or
a gap in the tests): docs/qualification/mutation.md keeps those judgements.
"""

from __future__ import annotations

import argparse
import ast
import json
import random
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Area:
    """One area of the campaign: the source mutated and the requirements whose traced tests
    must kill its mutants."""

    name: str
    #: the requirements file's area this one belongs to
    requirement_area: str
    #: ``path`` (a module, from the repository's root) or ``path::name`` (one of its
    #: top-level functions or classes)
    source: tuple[str, ...]
    tors: tuple[str, ...]
    #: the pytest marker expression of the test command (``not slow``: the long tests and the
    #: fixed sample of each slow test's cases, tests/conftest.py)
    markexpr: str = "not slow"


def _ids(prefix: str, *numbers: int) -> tuple[str, ...]:
    """``TOR-<prefix>-00n`` for each number."""
    return tuple(f"TOR-{prefix}-{n:03d}" for n in numbers)


AREAS: tuple[Area, ...] = (
    Area("grammar", "FRETish grammar", ("fretish/parser.py",), _ids("GRM", 1, 2, 3, 4)),
    Area("durations", "FRET semantics", ("compiler/semantics.py::duration_ticks",),
         _ids("SEM", 10)),
    Area("semantics", "FRET semantics", ("compiler/semantics.py", "compiler/scope_timing.py"),
         _ids("SEM", 1, 2, 3, 5, 6, 7, 8, 9)),
    Area("tick-rules", "Tick rules", ("signals/clock.py",), _ids("TCK", *range(1, 10))),
    # the module is also the three-valued logic of binding expressions over NaN
    # (TOR-DMG-004, TOR-VER-004)
    Area("bindings", "Signal bindings", ("signals/bindings/operations.py",),
         (*_ids("BND", 1, 2, 3, 4, 5), "TOR-DMG-004", "TOR-VER-004")),
    # the module is also the CSV trace's format (TOR-TCK-007)
    Area("log-readers", "Log readers", ("logs/csv/read.py",),
         (*_ids("LOG", 1, 2, 3), "TOR-TCK-007")),
    # the MCAP reader (chunks through the index or record by record, damage as gaps): the
    # same messages as the other containers (TOR-LOG-001), damage listed and never the end
    # (TOR-DMG-001), a chunk's declared size (TOR-DMG-005); TOR-DMG-002's traced tests are
    # left out (one of them, over CSV rows, takes 48 s)
    Area("mcap-reader", "Log readers", ("logs/mcap/source.py",),
         ("TOR-LOG-001", *_ids("DMG", 1, 5))),
    # the module is also the LTL3 verdict (TOR-VER-009), streamed by the CSV audit
    # (TOR-LOG-003), and the robustness (TOR-VER-007)
    Area("judge", "Verdicts", ("monitors/judge.py",),
         (*_ids("VER", 1, 2, 3, 4, 7, 9), "TOR-LOG-003")),
    # Kleene's reading of the pt formula over unknown ticks (a gap, NaN) and the LTL3 verdict
    # over every letter an unknown tick may be: the damage's verdicts (TOR-DMG-002, 004) by
    # the three-valued rule (TOR-VER-004)
    Area("damage", "Damage and gaps", ("monitors/three_valued.py",),
         (*_ids("DMG", 2, 4), "TOR-VER-004")),
    Area("verdict-words", "Verdicts",
         ("audit/verdict.py::Verdict", "audit/verdict.py::incomplete",
          "audit/verdict.py::summary", "audit/verdict.py::exit_code"),
         _ids("VER", 1, 2, 3, 5, 6)),
    Area("generation", "Generated monitors", ("compiler/codegen.py",), _ids("GEN", 1, 2, 5)),
    Area("c2po", "Generated monitors", ("compiler/c2po.py",), _ids("GEN", 6)),
    # the C99 monitors (TOR-GEN-003), also traced by their tests to the pt step and verdict
    # (TOR-GEN-001) and the escaping of ids and texts (TOR-GEN-005)
    Area("c-generation", "Generated monitors", ("compiler/c_codegen.py",), _ids("GEN", 1, 3, 5)),
    Area("shield", "Shield", ("shield/build.py",), _ids("SHD", *range(1, 8))),
    Area("check", "fretc check", ("check/checker.py",), _ids("CHK", 1, 2, 3)),
    Area("watch", "fretc watch", ("live/watch.py",), _ids("WCH", 1, 2)),
    # the areas of the requirements the ones above leave out: the formulas' printers (ft_inf
    # in Spot's syntax, FRET's codes for names), AJPF's properties, the statistical verdict,
    # the obligations open at a cut, the gaps bridged, the output files, the audit document's
    # schema, the kit
    Area("printers", "FRET semantics", ("compiler/printers.py",), _ids("SEM", 4, 12)),
    Area("psl", "Generated monitors", ("compiler/ajpf.py",), _ids("GEN", 4)),
    Area("statistics", "Verdicts", ("audit/fleet/statistics.py",),
         ("TOR-VER-010", "TOR-SEM-011")),
    Area("open-obligations", "Damage and gaps", ("monitors/obligations.py",), _ids("DMG", 3)),
    # the gaps of a log: the ticks they make unknown (TOR-DMG-002) and those bridged
    # (TOR-DMG-006)
    Area("gap-bridges", "Damage and gaps", ("audit/gaps.py",), _ids("DMG", 2, 6)),
    Area("outputs", "Outputs", ("common/outputs.py",), _ids("OUT", 1, 2)),
    # the Gwendolen agent (its machine in Java, its plans, the environment of AJPF's runs)
    Area("gwendolen", "Shield", ("shield/emit_gwendolen.py",), _ids("SHD", 6)),
    # the ROS 1 bag and rosbag2 readers: the same messages as the other containers
    Area("ros-bags", "Log readers", ("logs/ros/bags.py",), ("TOR-LOG-001",)),
    # the audit document read back by report and export against its JSON Schema
    Area("audit-json", "Verdicts", ("reports/files.py",), _ids("VER", 8)),
    # the validation suite's verdict per requirement and its mutation run (the kit itself)
    Area("kit", "Qualification kit", ("qualification/suite.py",), _ids("QUA", 1)),
)


def traced_tests(tors: tuple[str, ...], tests: Path) -> list[str]:
    """The node ids of the tests under ``tests`` (a clone's) that carry a tor marker of one
    of ``tors`` (sorted), read by that clone's ``tor_matrix.py``."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"tor_matrix_{abs(hash(tests))}",
                                                  tests / "tor_matrix.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    wanted = set(tors)
    return sorted(n for n, ids in module.markers(tests).items() if wanted & set(ids))


def _modules(area: Area) -> list[str]:
    """The module files an area mutates (each once, in the table's order)."""
    return list(dict.fromkeys(s.split("::")[0] for s in area.source))


def line_ranges(area: Area, clone: Path) -> dict[str, list[tuple[int, int]] | None]:
    """``{module: [(first line, last line), ...]}`` of the definitions an area keeps (None:
    the whole module)."""
    out: dict[str, list[tuple[int, int]] | None] = {}
    for entry in area.source:
        path, _, name = entry.partition("::")
        if not name:
            out[path] = None
            continue
        tree = ast.parse((clone / path).read_text(encoding="utf-8"))
        spans = [(n.lineno if not getattr(n, "decorator_list", None)
                  else min(d.lineno for d in n.decorator_list), n.end_lineno or n.lineno)
                 for n in tree.body if getattr(n, "name", None) == name]
        if not spans:
            raise SystemExit(f"{area.name}: no top-level {name} in {path}")
        ranges = out.setdefault(path, [])
        if ranges is not None:
            ranges.extend(spans)
    return out


def test_command(python: str, clone: Path, area: Area, nodes: list[str]) -> str:
    """The shell-free command cosmic-ray runs for each mutant (it splits it with shlex)."""
    import shlex

    args = ["env", f"PYTHONPATH={clone / 'src'}", python, "-m", "pytest", "-x", "-q",
            "-p", "no:cacheprovider", "-n", "0", "-m", area.markexpr, *nodes]
    return shlex.join(args)


def baseline(command: str, python: str, clone: Path) -> float:
    """Run the unmutated tests in the clone; return their wall time in seconds. Exits when
    they fail or when fretc is not imported from the clone."""
    import shlex

    env_python = shlex.split(command)[:3]
    where = subprocess.run([*env_python[:2], python, "-c", "import fretc; print(fretc.__file__)"],
                           cwd=clone, capture_output=True, text=True, check=True).stdout.strip()
    if not Path(where).resolve().is_relative_to(clone.resolve()):
        raise SystemExit(f"fretc is imported from {where}, not from the clone {clone}")
    start = time.perf_counter()
    run = subprocess.run(shlex.split(command), cwd=clone, capture_output=True, text=True,
                         env={**_environ(), "PYTHONDONTWRITEBYTECODE": "1"})
    took = time.perf_counter() - start
    if run.returncode != 0:
        raise SystemExit(f"the baseline fails in {clone}:\n{run.stdout[-3000:]}")
    return took


def _environ() -> dict[str, str]:
    """This process's environment."""
    import os

    return dict(os.environ)


def write_config(clone: Path, area: Area, command: str, timeout: float) -> Path:
    """Write the area's cosmic-ray configuration into the clone; return its path."""
    def q(s: str) -> str:
        return json.dumps(s)  # a TOML basic string is a JSON string

    modules = ", ".join(q(m) for m in _modules(area))
    text = ("[cosmic-ray]\n"
            f"module-path = [{modules}]\n"
            f"timeout = {timeout:.1f}\n"
            "excluded-modules = []\n"
            f"test-command = {q(command)}\n\n"
            "[cosmic-ray.distributor]\n"
            'name = "local"\n')
    path = clone / "cosmic-ray.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _in_ranges(line_from: int, line_to: int, ranges: list[tuple[int, int]] | None) -> bool:
    """Whether a mutation's lines meet one of the ranges (None: the whole module)."""
    return ranges is None or any(line_from <= b and a <= line_to for a, b in ranges)


Span = tuple[tuple[int, int], tuple[int, int]]
#: the output of the skipped results of mutants inside an annotation
ANNOTATION = "mutation_campaign: an annotation, never evaluated (equivalent)"


def annotation_spans(path: Path) -> list[Span]:
    """The (line, column) spans of a module's annotations when the module postpones their
    evaluation (``from __future__ import annotations``): a mutant inside one changes a string
    nobody evaluates, an equivalent mutant. Empty for a module that evaluates them. (Columns
    are the ast's, UTF-8 bytes; cosmic-ray's count characters: the same on ASCII lines.)"""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    if not any(isinstance(n, ast.ImportFrom) and n.module == "__future__"
               and any(a.name == "annotations" for a in n.names) for n in tree.body):
        return []
    notes: list[ast.expr] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            notes += [x.annotation for x in (*a.posonlyargs, *a.args, *a.kwonlyargs,
                                             a.vararg, a.kwarg)
                      if x is not None and x.annotation is not None]
            notes += [node.returns] if node.returns is not None else []
        elif isinstance(node, ast.AnnAssign):
            notes.append(node.annotation)
    return [((n.lineno, n.col_offset), (n.end_lineno or n.lineno, n.end_col_offset or 0))
            for n in notes]


def _place(item: Any) -> tuple[Any, ...]:
    """A work item's sort key from its mutations (file, position, operator, occurrence):
    cosmic-ray's job ids are random (uuid4), its mutations the same on every init."""
    return tuple((str(m.module_path), tuple(m.start_pos), tuple(m.end_pos), m.operator_name,
                  m.occurrence) for m in item.mutations)


def select(session: Path, ranges: dict[str, list[tuple[int, int]] | None],
           notes: dict[str, list[Span]], sample: int | None, seed: int) -> dict[str, int]:
    """Mark skipped in the session the work items outside the area, those inside an
    annotation (``notes``, :func:`annotation_spans`) and those the sample leaves out; return
    the counts of mutants in the area, in its annotations, and kept."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import WorkerOutcome, WorkResult

    def noted(m: Any) -> bool:
        return any(a <= tuple(m.start_pos) and tuple(m.end_pos) <= b
                   for a, b in notes.get(str(m.module_path), []))

    with use_db(str(session), WorkDB.Mode.open) as db:
        items = sorted(db.pending_work_items, key=_place)
        inside = [w.job_id for w in items
                  if all(_in_ranges(m.start_pos[0], m.end_pos[0], ranges.get(str(m.module_path)))
                         for m in w.mutations)]
        annotated = {w.job_id for w in items
                     if w.job_id in set(inside) and all(noted(m) for m in w.mutations)}
        rest = [j for j in inside if j not in annotated]
        kept = set(rest)
        if sample is not None and sample < len(rest):
            kept = set(random.Random(seed).sample(rest, sample))
        if annotated:
            db.set_multiple_results(sorted(annotated), WorkResult(
                worker_outcome=WorkerOutcome.SKIPPED, output=ANNOTATION))
        skip = [w.job_id for w in items if w.job_id not in kept and w.job_id not in annotated]
        if skip:
            db.set_multiple_results(skip, WorkResult(
                worker_outcome=WorkerOutcome.SKIPPED,
                output="mutation_campaign: outside the area or not sampled"))
    return {"mutants_in_area": len(inside), "annotation_mutants": len(annotated),
            "sampled": len(kept)}


def results(session: Path) -> dict[str, Any]:
    """The counts and the survivors of a session whose work is done."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome, WorkerOutcome

    counts = {"run": 0, "killed": 0, "survived": 0, "timeout": 0, "incompetent": 0,
              "skipped": 0}
    survivors = []
    with use_db(str(session), WorkDB.Mode.open) as db:
        for item, result in db.completed_work_items:
            if result.worker_outcome == WorkerOutcome.SKIPPED:
                counts["skipped"] += 1
                continue
            counts["run"] += 1
            if result.worker_outcome != WorkerOutcome.NORMAL \
                    or result.test_outcome == TestOutcome.INCOMPETENT:
                counts["incompetent"] += 1
            elif result.test_outcome == TestOutcome.SURVIVED:
                counts["survived"] += 1
                m = item.mutations[0]
                survivors.append({"file": str(m.module_path), "line": m.start_pos[0],
                                  "operator": m.operator_name, "occurrence": m.occurrence,
                                  "job_id": item.job_id, "diff": result.diff})
            elif result.output == "timeout":
                counts["timeout"] += 1
            else:
                counts["killed"] += 1
    survivors.sort(key=lambda s: (s["file"], s["line"], s["operator"], s["occurrence"]))
    return {**counts, "survivors": survivors}


def run_area(area: Area, args: argparse.Namespace) -> dict[str, Any]:
    """Clone, configure, baseline, init, select, exec and read back one area."""
    clone = Path(args.work) / area.name
    if clone.exists():
        shutil.rmtree(clone)
    clone.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    # the tests that read ../shared (real logs, FRET's projects) find it beside the clone as
    # beside this repository: without it they skip, and a mutant they would kill survives
    shared, beside = ROOT.parent / "shared", clone.parent / "shared"
    if shared.is_dir() and not beside.exists():
        beside.symlink_to(shared, target_is_directory=True)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=clone, capture_output=True,
                            text=True, check=True).stdout.strip()
    nodes = traced_tests(area.tors, clone / "tests")
    if not nodes:
        raise SystemExit(f"{area.name}: no traced tests of {', '.join(area.tors)}")
    command = test_command(args.python, clone, area, nodes)
    took = baseline(command, args.python, clone)
    timeout = max(args.timeout_factor * took, 10.0)
    config = write_config(clone, area, command, timeout)
    session = clone / "session.sqlite"
    bindir = Path(sys.executable).parent
    subprocess.run([str(bindir / "cosmic-ray"), "init", str(config), str(session)],
                   cwd=clone, check=True)
    notes = {m: annotation_spans(clone / m) for m in _modules(area)}
    counts = select(session, line_ranges(area, clone), notes, args.sample, args.seed)
    start = time.perf_counter()
    subprocess.run([str(bindir / "cosmic-ray"), "exec", str(config), str(session)],
                   cwd=clone, check=True)
    return {"area": area.name, "requirement_area": area.requirement_area,
            "source": list(area.source), "tors": list(area.tors), "tests": nodes,
            "commit": commit, "baseline_s": round(took, 1), "timeout_s": round(timeout, 1),
            "exec_s": round(time.perf_counter() - start, 1), **counts,
            "sample": args.sample, "seed": args.seed,
            "test_command": command, **results(session)}


def table(report: list[dict[str, Any]]) -> str:
    """The report as a plain-text table."""
    cols = ("area", "mutants_in_area", "annotation_mutants", "run", "killed", "survived",
            "timeout", "incompetent")
    head = ("area", "in area", "annotations", "run", "killed", "survived", "timeout",
            "incompetent")
    rows = [head] + [tuple(str(r[c]) for c in cols) for r in report]
    widths = [max(len(r[i]) for r in rows) for i in range(len(cols))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in rows)


def main(argv: list[str] | None = None) -> int:
    """Run the campaign over the areas named (all with --all) and write the JSON report."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("areas", nargs="*", help="areas of AREAS to run")
    p.add_argument("--all", action="store_true", help="run every area")
    p.add_argument("--list", action="store_true", help="print the areas and exit")
    p.add_argument("--sample", type=int, help="run N mutants of each area (seeded choice)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--timeout-factor", type=float, default=3.0)
    p.add_argument("--python", default=str(ROOT / ".venv" / "bin" / "python"),
                   help="the Python fretc's tests run with (fretc's environment)")
    p.add_argument("--work", default="/tmp/mut", help="folder of the scratch clones")
    p.add_argument("-o", "--output", help="JSON report (default: standard output)")
    args = p.parse_args(argv)
    by_name = {a.name: a for a in AREAS}
    if args.list:
        for a in AREAS:
            print(f"{a.name:14} {', '.join(a.source)}  <- {', '.join(a.tors)}")
        return 0
    unknown = [n for n in args.areas if n not in by_name]
    if unknown or not (args.areas or args.all):
        p.error(f"name areas of --list (unknown: {', '.join(unknown)})" if unknown
                else "name areas, or --all")
    chosen = list(AREAS) if args.all else [by_name[n] for n in args.areas]
    report = [run_area(a, args) for a in chosen]
    text = json.dumps({"tool": "cosmic-ray " + _version(), "areas": report}, indent=1)
    if args.output:
        Path(args.output).write_text(text + "\n", encoding="utf-8")
    else:
        print(text)
    print(table(report), file=sys.stderr)
    return 0


def _version() -> str:
    """cosmic-ray's installed version."""
    from importlib.metadata import version

    return version("cosmic-ray")


if __name__ == "__main__":
    sys.exit(main())
