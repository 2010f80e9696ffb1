"""The validation suite's checks of fretc's other commands, end to end: ``fretc check``
(conflicts at any bound, realizability, witnesses the audit replays), the outputs every
command writes (the same bytes, never through a link), and ``fretc shield-replay`` over a
recording written here, whole and cut.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from fretc.qualification.checks import Check, Run
from fretc.qualification.checks_audit import fretc, verdicts
from fretc.qualification.checks_forms import _folder, shield_command
from fretc.qualification.checks_logs import MS, S, write_mcap


def _check(run: Run, folder: Path, name: str, text: str, *args: str
           ) -> tuple[int, dict[str, Any] | None, str]:
    """``fretc check --json`` of the requirements ``text`` written as ``name``: (exit code,
    its JSON or None, its output)."""
    path = folder / name
    path.write_text(text, encoding="utf-8")
    code, out = fretc(run, ["check", str(path), "--no-progress", "--json", *args])
    try:
        doc = json.loads(out[out.index("{"):])
    except ValueError:
        doc = None
    return code, doc, out


def _kinds(doc: dict[str, Any] | None) -> list[tuple[str, list[str]]]:
    """The findings of a check JSON as (kind, sorted requirement ids)."""
    return sorted((f["kind"], sorted(f["requirements"])) for f in (doc or {}).get("findings", []))


def check_conflicts(run: Run) -> list[str]:
    """A conflict past Spot's bound (``within 40 ticks satisfy p`` against ``always !p``) is
    found (exit 1, the pair named); with ``!p | q`` the set is consistent (exit 0, no
    finding); neither is answered unknown."""
    folder = _folder(run, "check-conflicts")
    out = []
    code, doc, text = _check(run, folder, "c.fret", "A: the sw shall within 40 ticks satisfy p\n"
                             "B: the sw shall always satisfy !p\n")
    if code != 1 or ("conflict", ["A", "B"]) not in _kinds(doc):
        out.append(f"within 40 ticks p and always !p: exit {code}, findings {_kinds(doc)}; "
                   f"expected 1 with the conflict of A and B: {text.strip()[-200:]}")
    code, doc, text = _check(run, folder, "ok.fret", "A: the sw shall within 40 ticks satisfy p\n"
                             "B: the sw shall always satisfy !p | q\n")
    if code != 0 or _kinds(doc):
        out.append(f"a consistent set: exit {code}, findings {_kinds(doc)}; expected 0, none")
    return out


def check_realizability(run: Run) -> list[str]:
    """Two requirements no controller meets together (``o`` when ``a``, ``!o`` when ``b``,
    inputs first) are unrealizable (exit 1), each alone realizable (exit 0); a variable
    declared neither input nor output is not decided (exit 2)."""
    folder = _folder(run, "check-realizability")
    both = ("R1: whenever a ctrl shall immediately satisfy o\n"
            "R2: whenever b ctrl shall immediately satisfy !o\n")
    io = ["--inputs", "a,b", "--outputs", "o"]
    out = []
    code, doc, text = _check(run, folder, "r.fret", both, *io)
    if code != 1 or ("unrealizable", ["R1", "R2"]) not in _kinds(doc):
        out.append(f"R1 and R2: exit {code}, findings {_kinds(doc)}; expected 1, unrealizable")
    code, doc, text = _check(run, folder, "r1.fret", both.splitlines()[0] + "\n", *io)
    if code != 0:
        out.append(f"R1 alone: exit {code}, expected 0 (realizable): {text.strip()[-200:]}")
    code, doc, text = _check(run, folder, "u.fret", both, "--inputs", "a", "--outputs", "o")
    if code != 2:
        out.append(f"b declared neither input nor output: exit {code}, expected 2")
    return out


def check_witnesses(run: Run) -> list[str]:
    """Each finding's witness (``--witness-dir``: a vacuous requirement, an unrealizable
    pair), audited against the requirements, gives the verdicts the finding expects."""
    folder = _folder(run, "check-witnesses")
    cases = {"v.fret": ("C1: the sw shall always satisfy p\n"
                        "C2: upon q the sw shall immediately satisfy !p\n", ()),
             "r.fret": ("R1: whenever a ctrl shall immediately satisfy o\n"
                        "R2: whenever b ctrl shall immediately satisfy !o\n",
                        ("--inputs", "a,b", "--outputs", "o"))}
    out: list[str] = []
    for name, (text, extra) in cases.items():
        wdir = folder / f"{name}.witnesses"
        code, doc, said = _check(run, folder, name, text, "--witness-dir", str(wdir), *extra)
        found = [f for f in (doc or {}).get("findings", []) if f.get("witness")]
        if not found:
            out.append(f"{name}: no finding with a witness (exit {code}): {said.strip()[-200:]}")
        for f in found:
            csv = Path(f["witness"])
            if not csv.is_absolute() and not csv.exists():
                csv = wdir / csv.name
            jpath = folder / f"{csv.stem}.json"
            fretc(run, ["audit", "-r", str(folder / name), str(csv), "--json", str(jpath),
                        "--no-progress"])
            doc2 = json.loads(jpath.read_text("utf-8")) if jpath.exists() else None
            got = {rid: v.get("verdict") for (_, rid), v in verdicts(doc2).items()}
            want = f["expected"]
            if any(got.get(rid) != w for rid, w in want.items()):
                out.append(f"{name}: the witness {csv.name} audits to {got}, the finding "
                           f"expects {want}")
    return out


def check_outputs(run: Run) -> list[str]:
    """Two runs of ``fretc audit --json`` and ``--emit c`` on the same inputs write the same
    bytes; a link planted at an output's name is replaced by the file, its target untouched."""
    folder = _folder(run, "outputs")
    (folder / "r.fret").write_text("R1: upon c the sw shall within 2 ticks satisfy r\n",
                                   encoding="utf-8")
    (folder / "t.csv").write_text("c,r\ntrue,false\nfalse,false\nfalse,true\n", "utf-8")
    target = folder / "target.txt"
    target.write_text("keep\n", encoding="utf-8")
    (folder / "b.json").symlink_to(target)
    out = []
    for name in ("a.json", "b.json"):
        fretc(run, ["audit", "-r", str(folder / "r.fret"), str(folder / "t.csv"), "--json",
                    str(folder / name), "--no-progress"])
    for name in ("c1", "c2"):
        fretc(run, [str(folder / "r.fret"), "--emit", "c", "-o", str(folder / name)])
    a, b = folder / "a.json", folder / "b.json"
    if not a.exists() or b.is_symlink() or not b.exists() or a.read_bytes() != b.read_bytes():
        out.append("two audits of the same inputs differ, or the second wrote through the link")
    if target.read_text("utf-8") != "keep\n":
        out.append("the link's target was written")
    one = {p.name: p.read_bytes() for p in (folder / "c1").iterdir()}
    two = {p.name: p.read_bytes() for p in (folder / "c2").iterdir()}
    if not one or one != two:
        out.append(f"two runs of --emit c differ ({sorted(one)} vs {sorted(two)})")
    return out


def check_shield_replay(run: Run) -> list[str]:
    """``fretc shield-replay`` of the ``shield-python`` check's shield over a recording whose
    controller never sets ``o`` while ``x > 5`` at 1.3 .. 1.6 s: the recording is violated,
    the shielded run satisfied (exit 0); the recording cut at 60 % replays to its damage
    (exit 3, the shielded run partial, never satisfied whole)."""
    folder = _folder(run, "shield-replay")
    code, text = fretc(run, [*shield_command(folder, "/o.data > 0.5"), "--emit", "python",
                             "-o", str(folder / "shield")])
    if code != 0:
        return [f"fretc shield exited {code}: {text.strip()[-300:]}"]
    msgs = sorted([("/x", S + k * 100 * MS, 9.0 if 3 <= k <= 6 else 1.0) for k in range(20)]
                  + [("/o", S + k * 100 * MS + MS, 0.0) for k in range(20)],
                  key=lambda m: m[1])
    rec = folder / "run.mcap"
    write_mcap(rec, msgs, chunk_size=512)
    out = []
    code, text = fretc(run, ["audit", "-r", str(folder / "s.fret"), "-b",
                             str(folder / "s.toml"), str(rec), "--no-progress"])
    if code != 1:
        out.append(f"the recording's own audit: exit {code}, expected 1 (violated)")
    jpath = folder / "replay.json"
    code, text = fretc(run, ["shield-replay", str(folder / "shield"), str(rec), "-o",
                             str(folder / "out"), "--json", str(jpath)])
    if code != 0:
        out.append(f"the shielded run: exit {code}, expected 0: {text.strip()[-300:]}")
    cut = folder / "cut.mcap"
    data = rec.read_bytes()
    cut.write_bytes(data[:int(len(data) * 0.6)])
    code, text = fretc(run, ["shield-replay", str(folder / "shield"), str(cut), "-o",
                             str(folder / "out-cut")])
    if code != 3:
        out.append(f"the cut recording: exit {code}, expected 3 (partial): "
                   f"{text.strip()[-300:]}")
    return out


def check_statistics(run: Run) -> list[str]:
    """``with probability >= 0.5`` audited over CSV runs: 19 of 20 runs satisfied (one
    violated) holds (exit 0, never violated by the one run), 7 of 10 is undecided (exit 5);
    each interval is the exact Clopper-Pearson interval at 95 % (scipy's ``binomtest``)."""
    try:
        from scipy.stats import binomtest
    except ImportError as exc:  # (scipy is a dependency of fretc)
        return [f"scipy cannot be imported: {exc}"]
    folder = _folder(run, "statistics")
    (folder / "p.fret").write_text("P: the sw shall, with probability >= 0.5, always "
                                   "satisfy r\n", encoding="utf-8")
    out = []
    for runs, held, want_code, want in ((20, 19, 0, "holds"), (10, 7, 5, "undecided")):
        logs = []
        for k in range(runs):
            path = folder / f"n{runs}-{k:02d}.csv"
            path.write_text("r\ntrue\n" + ("true\n" if k < held else "false\n"), "utf-8")
            logs.append(str(path))
        jpath = folder / f"n{runs}.json"
        code, text = fretc(run, ["audit", "-r", str(folder / "p.fret"), *logs, "--json",
                                 str(jpath), "--no-progress"])
        doc = json.loads(jpath.read_text("utf-8")) if jpath.exists() else {}
        stats = (doc.get("statistics") or [{}])[0]
        ci = binomtest(held, runs).proportion_ci(0.95, "exact")
        interval = stats.get("interval") or [None, None]
        close = all(isinstance(a, float) and abs(a - b) < 1e-9
                    for a, b in zip(interval, (ci.low, ci.high), strict=True))
        if (code, stats.get("verdict")) != (want_code, want) or not close:
            out.append(f"{held} of {runs}: exit {code}, {stats.get('verdict')}, interval "
                       f"{interval}; expected {want_code}, {want}, [{ci.low}, {ci.high}]")
    return out


def check_environment(run: Run) -> list[str]:
    """The report's record of the installation: fretc's version is the installed
    distribution's, the hash of its package's files is that of the files on disk now, a
    commit comes with the list of tracked files that differ from it (or None when git cannot
    say), and every dependency fretc declares is listed with its version and a SHA-256."""
    import re
    from importlib import metadata

    from fretc.qualification import environment

    env = environment.environment()
    origin, out = env["fretc"], []
    if origin["version"] != metadata.version("fretc"):
        out.append(f"version {origin['version']}, installed {metadata.version('fretc')}")
    if (origin["files_sha256"], origin["files"]) != environment.package_hash():
        out.append("the package files' hash is not that of the files on disk")
    if origin["commit"] is not None and not (origin["modified"] is None
                                             or isinstance(origin["modified"], list)):
        out.append(f"a commit without the list of files modified: {origin['modified']!r}")
    listed = {environment._normalized(d["name"]): d for d in env["distributions"]}
    for name in sorted(environment.requirement_names()):
        d = listed.get(name)
        if d is None or not re.fullmatch(r"[0-9a-f]{64}", str(d.get("sha256"))):
            out.append(f"the dependency {name} is not listed with its hash")
    return out


#: the checks of fretc check, the outputs and shield-replay, in the order they run
CHECKS: tuple[Check, ...] = (
    Check("check-conflicts", ("TOR-CHK-002",),
          "a conflict past Spot's bound found, a consistent set passed", check_conflicts),
    Check("check-realizability", ("TOR-CHK-003",),
          "an unrealizable pair, each alone realizable, an undeclared variable",
          check_realizability),
    Check("check-witnesses", ("TOR-CHK-001",),
          "each finding's witness audits to the verdicts it expects", check_witnesses),
    Check("outputs-same-bytes", ("TOR-OUT-002",),
          "the same inputs give the same bytes; a planted link is replaced", check_outputs),
    Check("audit-statistics", ("TOR-VER-010",),
          "a probability judged by exact Clopper-Pearson intervals", check_statistics),
    Check("shield-replay", ("TOR-SHD-007",),
          "a recording replayed through a shield, whole and cut", check_shield_replay),
    Check("qualify-environment", ("TOR-QUA-001",),
          "the report's record of the installation is the installation's", check_environment),
)
