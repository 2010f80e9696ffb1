"""The ``reqif``, ``doorstop``, ``exports`` and ``explain`` classes of ``bench/fuzz_hostile.py``
(its docstring): hostile requirement sources, exports and diagrams.

* ``reqif``: the StrictDoc ReqIF of ``tests/fixtures`` with one hostile change (a duplicated
  IDENTIFIER, control characters, a DTD with an entity, a random run of bytes overwritten, a
  huge attribute), or an XHTML value with deleted or hidden text at a random place. Oracle:
  the entries or an input error (no other exception), no entity expanded, text of a ``del``
  or hidden span never read.
* ``doorstop``: the Doorstop tree of ``tests/fixtures`` with one item damaged (invalid YAML,
  a ``!!python`` tag, not UTF-8, a wrong type, a YAML bomb, a FIFO, a link outside the tree,
  random bytes). Oracle: the entries or an input error within 20 s; no object built from a
  YAML tag (a file the tag would write is never written).
* ``exports``: results whose texts hold control characters, quotes, markup, surrogates and
  line breaks, exported into the ReqIF file, the Doorstop tree and a FRET export. Oracle: each
  output reads back (the ``reqif`` library, ``doorstop``, ``json``) to the same ids, and the
  exported values read back unchanged (line breaks as spaces in ReqIF attributes).
* ``explain``: ``fretc explain`` and ``fretc simulate`` of a random requirement (durations up
  to 10^6 ticks) and trace (NaN included). Oracle: exit 0 to 3, never an internal error, an
  SVG under 2 MB with no ``<script`` or event attribute.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIX = ROOT / "tests" / "fixtures" / "requirements_tools"
REQIF = FIX / "strictdoc" / "safe_ros.reqif"
DOORSTOP = FIX / "doorstop"
NASTY = ["\x01", "\x1b[31m", "\x7f", "\u202e", "<script>x</script>", '"', "'", "&amp;",
         "\n", "\t", "\ud800", "]]>", "{a: 1}", "- x", "# not a comment", "..."]


def _load(path) -> tuple[list, str | None]:
    from fretc.common.errors import FretishError
    from fretc.fretish.files import load_requirements

    try:
        return load_requirements([str(path)]), None
    except FretishError as exc:
        return [], str(exc)


def run_reqif(rng: random.Random, tmp: Path) -> list[str]:
    """One hostile ReqIF, or XHTML value (module docstring)."""
    if rng.random() < 0.3:
        return run_xhtml(rng, tmp)
    text = REQIF.read_text(encoding="utf-8")
    how = rng.choice(["dup", "control", "dtd", "bytes", "huge"])
    secret = "SECRETWORD"
    if how == "dup":
        ids = [x.split('"')[0] for x in text.split('<SPEC-OBJECT IDENTIFIER="')[1:]]
        a, b = rng.sample(ids, 2)
        text = text.replace(f'IDENTIFIER="{b}"', f'IDENTIFIER="{a}"', 1)
    elif how == "control":
        text = text.replace("the robot shall", "the robot\x01 shall", 1)
    elif how == "dtd":
        text = text.replace("<REQ-IF", f'<!DOCTYPE r [<!ENTITY e "{secret}">]>\n<REQ-IF', 1)
        text = text.replace("the robot shall", "the robot &e; shall", 1)
    elif how == "huge":
        text = text.replace('LONG-NAME="', 'LONG-NAME="' + "x" * 2_000_000, 1)
    path = tmp / "h.reqif"
    data = text.encode("utf-8")
    if how == "bytes":
        at = rng.randrange(len(data))
        data = data[:at] + bytes(rng.randrange(256) for _ in range(rng.choice((1, 8, 64)))) \
            + data[at + 8:]
    path.write_bytes(data)
    entries, _err = _load(path)
    return [f"reqif {how}: entity expanded into {e.id}" for e in entries
            if secret in (e.text or "")]


def run_xhtml(rng: random.Random, tmp: Path) -> list[str]:
    """An XHTML value with a hidden span at a random place: its word never formalized."""
    from fretc.fretish.sources.reqif_file import visible_text

    words = "the robot shall always satisfy ok".split()
    at = rng.randrange(1, len(words))
    hider = rng.choice(['<xhtml:del>', '<xhtml:span style="display:none">',
                        '<xhtml:span hidden="">', '<xhtml:span style="color:red; '
                        'visibility: hidden">'])
    close = "</xhtml:del>" if "del" in hider else "</xhtml:span>"
    markup = ("<xhtml:div>" + " ".join(words[:at]) + f" {hider}SECRETWORD{close} "
              + " ".join(words[at:]) + "</xhtml:div>")
    got = visible_text(markup)
    return [] if got == " ".join(words) else [f"xhtml: {markup!r} read as {got!r}"]


def _tree(tmp: Path) -> Path:
    out = tmp / "tree"
    if out.exists():
        shutil.rmtree(out)
    shutil.copytree(DOORSTOP, out)
    return out


def run_doorstop(rng: random.Random, tmp: Path) -> list[str]:
    """One hostile Doorstop tree (module docstring)."""
    tree = _tree(tmp)
    items = sorted(p for p in tree.rglob("*.yml") if not p.name.startswith("."))
    item = rng.choice(items)
    text = item.read_text(encoding="utf-8")
    canary = tmp / "canary"
    how = rng.choice(["yaml", "tag", "utf8", "type", "bomb", "fifo", "link", "bytes"])
    if how == "yaml":
        item.write_text(text + "\nbroken: [\n")
    elif how == "tag":
        item.write_text(text + f"\nx: !!python/object/apply:os.mkdir ['{canary}']\n")
    elif how == "utf8":
        item.write_bytes(text.encode() + b"\nx: \xff\xfe\n")
    elif how == "type":
        key = rng.choice(["level", "links", "active", "text", "header", "FRETish"])
        item.write_text(text + f"\n{key}: {rng.choice(['{a: 1}', '[1, [2]]', '5', 'null'])}\n")
    elif how == "bomb":
        bomb = "".join(f"{a}: &{a} [{', '.join([f'*{p}'] * 9) if p else 'x'}]\n"
                       for p, a in zip([None, "a", "b", "c", "d", "e", "f"], "abcdefg"))
        item.write_text(text + "\n" + bomb)
    elif how == "fifo":
        os.mkfifo(item.parent / "Z9.yml")
    elif how == "link":
        (tmp / "outside.yml").write_text("active: true\ntext: outside\n")
        os.symlink(tmp / "outside.yml", item.parent / "Z9.yml")
    else:
        data = bytearray(text.encode())
        for _ in range(rng.choice((1, 4, 16))):
            data[rng.randrange(len(data))] = rng.randrange(256)
        item.write_bytes(bytes(data))
    t0 = time.monotonic()
    _load(tree)
    bad = []
    if time.monotonic() - t0 > 20:
        bad.append(f"doorstop {how}: {time.monotonic() - t0:.0f} s")
    if canary.exists():
        bad.append(f"doorstop {how}: a YAML tag built an object (made {canary})")
    return bad


def _results(rng: random.Random, entries) -> dict:
    from fretc.reports.export_results import RequirementResult

    def nasty() -> str:
        return "".join(rng.choice(NASTY + ["a", "b", " "]) for _ in range(rng.randrange(12)))

    return {e.id: RequirementResult(
        id=e.id, tool_id=e.origin.tool_id if e.origin else None,
        verdict=rng.choice(["satisfied", "violated", "unknown"]), evidence=nasty(),
        ft=nasty(), pt=nasty(), audit_id="sha256:" + nasty(), audit_date="2026-11-24",
        runs=1) for e in entries}


def run_exports(rng: random.Random, tmp: Path) -> list[str]:
    """Hostile results exported into each format and read back (module docstring)."""
    from fretc.reports.export_doorstop import export_doorstop
    from fretc.reports.export_fret import export_fret
    from fretc.reports.export_reqif import export_reqif

    bad = []
    kind = rng.choice(["reqif", "doorstop", "fret"])
    if kind == "reqif":
        entries, _ = _load(REQIF)
        out, _n = export_reqif(str(REQIF), _results(rng, entries))
        path = tmp / "out.reqif"
        path.write_bytes(out)
        back, err = _load(path)
        if err or [e.id for e in back] != [e.id for e in entries]:
            bad.append(f"reqif export does not read back: {err}")
    elif kind == "doorstop":
        import doorstop

        entries, _ = _load(DOORSTOP)
        results = _results(rng, entries)
        out = tmp / f"tree_out_{rng.randrange(10**9)}"
        export_doorstop(str(DOORSTOP), str(out), results,
                        {e.id: e.origin.file for e in entries})
        tree = doorstop.build(cwd=str(out), root=str(out))
        for e in entries:
            got = tree.find_item(e.id).get("fretc_evidence")
            if got != results[e.id].evidence:
                bad.append(f"doorstop export: {e.id} evidence {got!r} != "
                           f"{results[e.id].evidence!r}")
        shutil.rmtree(out)
    else:
        src = tmp / "fret.json"
        src.write_text(json.dumps([{"reqid": "R1", "project": "P", "fulltext":
                                    "the sw shall always satisfy p"}]))
        entries, _ = _load(src)
        results = _results(rng, entries)
        out, _n = export_fret(str(src), results)
        back = json.loads(out.decode("utf-8"))
        if back[0]["fretc"]["evidence"] != results["R1"].evidence:
            bad.append("fret export: evidence changed")
    return bad


def run_explain(rng: random.Random, tmp: Path) -> list[str]:
    """``fretc explain`` / ``fretc simulate`` of a random requirement (module docstring)."""
    from click.testing import CliRunner

    from fretc.cli import main

    n = rng.choice([0, 1, 3, 40, 41, 1000, 10**6])
    timing = rng.choice([f"within {n} ticks", f"for {n} ticks", f"after {n} ticks",
                         "immediately", "eventually", "always", "until q"])
    cond = rng.choice(["", "upon p ", "whenever p "])
    fret = tmp / "e.fret"
    rid = rng.choice(["R1", "r1", "R-1.a", "R_1"])
    fret.write_text(f"{rid}: {cond}the sw shall {timing} satisfy q\n", encoding="utf-8")
    out = tmp / f"explain_{rng.randrange(10**9)}"
    if rng.random() < 0.5:
        args = ["explain", str(fret), "-o", str(out)]
    else:
        ticks = rng.randrange(0, 60)
        p = [rng.choice(["0", "1", "nan", "1e309", "-0"]) for _ in range(ticks)]
        q = [rng.choice(["0", "1", "nan"]) for _ in range(ticks)]
        trace = tmp / "t.sim"
        trace.write_text(f"p: {' '.join(p)}\nq: {' '.join(q)}\n", encoding="utf-8")
        args = ["simulate", str(fret), str(trace), "-o", str(out)]
    res = CliRunner().invoke(main, args)
    bad = []
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        bad.append(f"{args[0]}: {type(res.exception).__name__}: {res.exception}")
    elif res.exit_code not in (0, 1, 2, 3):
        bad.append(f"{args[0]}: exit {res.exit_code}: {res.output[-200:]!r}")
    for svg in out.rglob("*.svg") if out.exists() else []:
        data = svg.read_bytes()
        if len(data) > 2_000_000 or b"<script" in data.lower() or b" onload=" in data.lower():
            bad.append(f"{args[0]}: {svg.name} is {len(data)} bytes or holds live markup")
    shutil.rmtree(out, ignore_errors=True)
    return bad
