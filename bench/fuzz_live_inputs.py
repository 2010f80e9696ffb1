"""The ``ws`` and ``inputs`` classes of ``bench/fuzz_hostile.py`` (its docstring).

* ``ws``: a hostile Foxglove WebSocket server plays a random script on 127.0.0.1 (a
  publisher restart: unadvertise and advertise again on a new channel id, with or without a
  pause; a frame nested 200,000 deep; a schema of up to 2 MB; messages with old, equal or
  huge log times; payloads cut short; values that violate ``a > 0``; an orderly close or
  none) and ``fretc watch`` watches it for ``--duration 3``. The oracle: no traceback; the
  watch ends within its duration plus 10 s; ``RA: always a > 0`` is never ``satisfied``
  with exit 0 when the script lost messages of ``/a`` (a restart, an undecodable payload,
  a violating value) or was cut short; ``violated`` only when a violating value was sent.
* ``bus``: hostile publishers on the robot's own middleware (Cyclone DDS or Zenoh, chosen at
  random, in this process on 127.0.0.1): good and violating values of ``/a``, payloads of
  random bytes, ``/a``'s publisher leaving and coming back (with or without a pause), the
  publisher of ``/b`` (which ``RA`` does not read) leaving while ``/a`` goes on, floods of
  good values; the watch runs for ``--duration 4``. The oracle is ``ws``'s, and ``RA`` is
  never judged on a value of ``/b``'s publisher's leaving.
* ``typed``: one command fed a wrongly typed input (every TOML / JSON type, surrogates,
  NUL, control characters, out-of-range numbers) in one place: a FRET JSON field
  (``--emit ltl``, ``--emit monitor``, ``check``), a binding file key (``audit``), a
  ``--psl-map`` key (``--emit psl``), a falsify space key (the space loader ``falsify``
  runs first). The oracle: exit 0, 1, 2 or 3, never an internal error or a traceback, and
  an exit 2 names the file.
"""

from __future__ import annotations

import asyncio
import json
import random
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "live"))

MS = 1_000_000
T0 = 1_700_000_000_000_000_000
FRET = "@tick_period 100 ms\nRA: the robot shall always satisfy a_ok\n"
BINDINGS = '[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\na_ok = "/a.data > 0"\n'

#: values of every TOML/JSON type and hostile strings (the ``typed`` class)
VALUES = [None, True, False, 0, -1, 2**63, 1e308, float("inf"), float("nan"), 1.5, [], [1],
          ["a", 2], {}, {"a": 1}, "", "\ud800", "a\x00b", "a\nb", "\x1b[31m", "x" * 5000,
          "100 ms", "-5 s", "1e400 s"]


# --------------------------------------------------------------------------- ws
def _script(rng: random.Random):
    """A random hostile script and what it did: (script, facts)."""
    from hostile_ws import advertise, f64, message_data, subscription

    facts = {"lost": False, "violating": False, "closed": rng.random() < 0.7}
    steps = [rng.choice(["good", "good", "bad_value", "restart", "cut_payload", "deep",
                         "big_schema", "old_times", "huge_time"]) for _ in range(rng.randrange(1, 6))]
    pause = rng.choice([0.0, 0.0, 0.3, 1.0])

    async def script(ws, k):
        if k > 0:  # a reconnection: nothing more
            await asyncio.sleep(5)
            return
        cid, t = 1, T0
        await ws.send(advertise([(cid, "/a")]))
        sid = await subscription(ws, cid)
        for step in steps:
            if step in ("good", "bad_value", "old_times"):
                x = -1.0 if step == "bad_value" else 1.0
                for _i in range(5):
                    lt = t - 10_000 * MS if step == "old_times" else t
                    await ws.send(message_data(sid, lt, f64(x)))
                    t += 50 * MS
                    await asyncio.sleep(0.002)
            elif step == "huge_time":
                await ws.send(message_data(sid, 2**64 - 1, f64(1.0)))
            elif step == "cut_payload":
                await ws.send(message_data(sid, t, b"\x00\x01\x00\x00\x00"))
                t += 50 * MS
            elif step == "deep":
                await ws.send("[" * 200_000 + "]" * 200_000)
            elif step == "big_schema":
                ch = json.loads(advertise([(99, "/big")]))
                ch["channels"][0]["schema"] = "float64 x\n" * rng.choice([10, 100_000, 200_000])
                await ws.send(json.dumps(ch))
            elif step == "restart":
                await ws.send(json.dumps({"op": "unadvertise", "channelIds": [cid]}))
                await asyncio.sleep(pause)
                cid += 1
                await ws.send(advertise([(cid, "/a")]))
                try:
                    sid = await subscription(ws, cid, timeout=3)
                except (TimeoutError, ConnectionError):
                    return
        await asyncio.sleep(0.2)
        if facts["closed"]:
            await ws.close(1000, "end of the run")
        else:
            await asyncio.sleep(10)

    sent = [i for i, s in enumerate(steps) if s in ("good", "bad_value", "old_times")]
    for i, s in enumerate(steps):
        # a restart loses what the publisher did not send in between: only a hole when
        # messages come on both sides of it
        hole = s == "restart" and sent and sent[0] < i < sent[-1]
        facts["lost"] |= bool(hole) or s in ("cut_payload", "bad_value")
        facts["violating"] |= s == "bad_value"
    return script, facts


def run_ws(rng: random.Random, tmp: Path) -> list[str]:
    """One ``ws`` input (module docstring); the unsupported outcomes."""
    from fretc.audit import AuditConfig, load_plan
    from fretc.audit.verdict import exit_code
    from hostile_ws import ScriptServer
    from fretc.live.watch import Watch, WatchOptions

    d = tmp / "ws"
    d.mkdir(exist_ok=True)
    (d / "w.fret").write_text(FRET)
    (d / "w.bindings.toml").write_text(BINDINGS)
    plan = load_plan(AuditConfig(requirements=(str(d / "w.fret"),)))
    script, facts = _script(rng)
    duration = 3.0
    with ScriptServer(script, lifetime=30) as srv:
        w = Watch(plan, WatchOptions(url=srv.url, wait=2.0, backoff=0.02, max_backoff=0.05,
                                     duration=duration,
                                     restart_grace=rng.choice([0.0, 0.5, 2.0])))
        t0 = time.monotonic()
        la = w.run()
        took = time.monotonic() - t0
    out = []
    if took > duration + 10:
        out.append(f"the watch took {took:.1f} s for --duration {duration}")
    (v,) = la.verdicts
    code = exit_code([la])
    if v.verdict == "satisfied" and code == 0 and facts["lost"]:
        out.append(f"satisfied with exit 0 though /a lost messages ({facts})")
    if v.verdict == "violated" and not facts["violating"]:
        out.append(f"violated though no violating value was sent ({facts})")
    return out


# --------------------------------------------------------------------------- bus
def _bus_server(transport: str, rng: random.Random, dds_xml: Path):
    """(URL, server) of a DDS domain or a Zenoh router on a free port of 127.0.0.1."""
    import socket

    if transport == "dds":
        from fretc.live.dds.serve import DdsServer

        url = f"dds://{rng.randrange(100, 230)}"
        return url, DdsServer(url, str(dds_xml))
    from fretc.live.zenoh.serve import ZenohServer

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        url = f"zenoh://127.0.0.1:{sock.getsockname()[1]}"
    return url, ZenohServer(url)


def _bus_lost(done: list[str], grace: float, pause: float) -> tuple[bool, bool]:
    """(whether ``/a`` lost messages the run should have had, whether that is ambiguous)
    from the steps that reached the bus. On DDS and Zenoh every bound publisher gone past
    the grace period is the run's end: a restart slower than the grace ends the run there;
    one close to it may or may not (discovery takes some time)."""
    ambiguous = False
    if "restart" in done:
        margin = grace - pause
        if grace == 0 or margin <= 0:
            done = done[:done.index("restart")]
        elif margin < 0.5:
            ambiguous = True
    sent = [i for i, s in enumerate(done) if s in ("good", "bad_value", "flood")]
    lost = False
    for i, s in enumerate(done):
        hole = s == "restart" and sent and sent[0] < i < sent[-1]
        lost |= bool(hole) or s in ("garbage", "bad_value")
    return lost, ambiguous


def _bus_publish(server, steps: list[str], schema: tuple, pause: float,
                 rng: random.Random, done: list[str]) -> None:
    """Play ``steps`` on ``server`` (``/a`` and ``/b``), appending to ``done`` what reached
    the bus; the server stops at the end."""
    import struct

    def f64(x: float) -> bytes:
        return b"\x00\x01\x00\x00" + struct.pack("<d", x)

    try:
        server.wait_subscribed(["/a"], timeout=10)
        t = T0
        for step in steps:
            if step in ("good", "bad_value"):
                for _ in range(5):
                    server.log("/a", f64(-1.0 if step == "bad_value" else 1.0), t)
                    server.log("/b", f64(1.0), t + 1)
                    t += 50 * MS
                    time.sleep(0.01)
            elif step == "flood":
                for _ in range(2000):
                    server.log("/a", f64(1.0), t)
                    t += MS
            elif step == "garbage":
                try:
                    server.log("/a", bytes(rng.randrange(256)
                                           for _ in range(rng.randrange(12))), t)
                except RuntimeError:  # Cyclone DDS checks a raw sample's header
                    done.append("refused")
                    continue
                t += 50 * MS
            elif step == "restart":
                server.unpublish("/a")
                time.sleep(pause)
                server.channel("/a", *schema)
                server.wait_subscribed(["/a"], timeout=3)
            elif step == "b_leaves":
                server.unpublish("/b")
            done.append(step)
        time.sleep(0.3)
    finally:
        server.stop()


def run_bus(rng: random.Random, tmp: Path) -> list[str]:
    """One ``bus`` input (module docstring); the unsupported outcomes."""
    import threading

    from fretc.audit import AuditConfig, load_plan
    from fretc.audit.verdict import exit_code
    from fretc.live.dds.idl_types import LOOPBACK_XML
    from fretc.live.watch import Watch, WatchOptions

    d = tmp / "bus"
    d.mkdir(exist_ok=True)
    (d / "w.fret").write_text(FRET)
    (d / "w.bindings.toml").write_text(BINDINGS + 'b_ok = "/b.data > 0"\n')
    (d / "dds.xml").write_text(LOOPBACK_XML)
    plan = load_plan(AuditConfig(requirements=(str(d / "w.fret"),)))
    transport = rng.choice(["dds", "zenoh"])
    url, server = _bus_server(transport, rng, d / "dds.xml")
    schema = ("cdr", "std_msgs/msg/Float64", "ros2msg", b"float64 data")
    for topic in ("/a", "/b"):
        server.channel(topic, *schema)
    steps = [rng.choice(["good", "good", "bad_value", "garbage", "restart", "b_leaves",
                         "flood"]) for _ in range(rng.randrange(1, 6))]
    pause = rng.choice([0.0, 0.3, 1.0])
    grace = rng.choice([0.0, 0.5, 2.0])
    facts = {"lost": False, "violating": "bad_value" in steps, "transport": transport,
             "steps": steps, "done": [], "pause": pause, "grace": grace}

    th = threading.Thread(target=_bus_publish, daemon=True,
                          args=(server, steps, schema, pause, rng, facts["done"]))
    th.start()
    duration = 4.0
    w = Watch(plan, WatchOptions(url=url, wait=3.0, duration=duration,
                                 config=str(d / "dds.xml") if transport == "dds" else None,
                                 restart_grace=grace))
    t0 = time.monotonic()
    la = w.run()
    took = time.monotonic() - t0
    th.join(15)
    # what reached the bus (a sample Cyclone DDS refused did not)
    facts["lost"], ambiguous = _bus_lost(facts["done"], grace, pause)
    out = []
    if took > duration + 10:
        out.append(f"the watch took {took:.1f} s for --duration {duration}")
    (v,) = la.verdicts
    code = exit_code([la])
    if v.verdict == "satisfied" and code == 0 and facts["lost"] and not ambiguous:
        out.append(f"satisfied with exit 0 though /a lost messages ({facts})")
    if v.verdict == "violated" and not facts["violating"]:
        out.append(f"violated though no violating value was sent ({facts})")
    return out


# --------------------------------------------------------------------------- inputs
def _fret_json(rng: random.Random, path: Path) -> list[str]:
    obj = {"reqid": "R1", "fulltext": "the sw shall always satisfy p"}
    obj[rng.choice(["reqid", "fulltext", "project", "rationale", "parent_reqid",
                    "semantics"])] = rng.choice(VALUES)
    path.write_text(json.dumps([obj] if rng.random() < 0.8 else obj))
    form = rng.choice([["--emit", "ltl"], ["--emit", "monitor", "-o", str(path.parent / "m.py")],
                       ["check"]])
    return (["check", str(path)] if form == ["check"] else [str(path)] + form)


def _toml_value(v) -> str:
    if v is None:
        return '"null"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v != v:
        return "nan"
    if isinstance(v, float) and v in (float("inf"), -float("inf")):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    return json.dumps(v)  # a TOML basic string is a JSON string (escapes alike)


def _bindings(rng: random.Random, d: Path) -> list[str]:
    table, key = rng.choice([("tick", "period"), ("tick", "topic"), ("tick", "time"),
                             ("tick", "nan"), ("tick", "inf"), ("tick", "header_lag"),
                             ("tick", "nominal_rate"), ("variables", "a_ok"),
                             ("logs", "glob"), ("types", "msg_path")])
    doc = {"tick": {"period": '"100 ms"', "time": '"log"'},
           "variables": {"a_ok": '"/a.data > 0"'}}
    doc.setdefault(table, {})[key] = _toml_value(rng.choice(VALUES))
    if key == "topic":
        doc["tick"].pop("period")
    text = "".join(f"[{t}]\n" + "".join(f"{k} = {v}\n" for k, v in kv.items())
                   for t, kv in doc.items())
    (d / "r.fret").write_text(FRET)
    (d / "r.bindings.toml").write_text(text, encoding="utf-8", errors="surrogatepass")
    log = ROOT / "traces" / "stop_delay.mcap"
    return ["audit", "--requirements", str(d / "r.fret"), "-b", str(d / "r.bindings.toml"),
            str(log), "--no-progress"]


def _psl_map(rng: random.Random, d: Path) -> list[str]:
    (d / "p.fret").write_text("R1: the sw shall always satisfy p\n")
    key = rng.choice(["agent", "variables", "comparisons"])
    value = rng.choice(VALUES + [{"p": rng.choice(VALUES)}])
    (d / "p.toml").write_text(f"{key} = {_toml_value(value)}\n", encoding="utf-8",
                              errors="surrogatepass")
    return [str(d / "p.fret"), "--emit", "psl", "--psl-map", str(d / "p.toml")]


def _space(rng: random.Random, d: Path) -> Path:
    lines = {"scenario": '"nominal"', "seed": "1", "max_time": "20.0"}
    params = {"obstacle_x": "[0.7, 1.8]"}
    where = rng.choice(["scenario", "seed", "max_time", "obstacle_x", "new"])
    v = _toml_value(rng.choice(VALUES + [[1e300, -1e300], [2.0, 1.0], [0.0, 1e-300]]))
    if where in lines:
        lines[where] = v
    else:
        params[where] = v
    text = "".join(f"{k} = {x}\n" for k, x in lines.items()) + "[parameters]\n" + \
        "".join(f"{k} = {x}\n" for k, x in params.items())
    p = d / "s.toml"
    p.write_text(text, encoding="utf-8", errors="surrogatepass")
    return p


def run_inputs(rng: random.Random, tmp: Path) -> list[str]:
    """One ``typed`` input (module docstring); what went wrong."""
    from click.testing import CliRunner

    from fretc.cli import main

    d = tmp / f"in{rng.randrange(10**9)}"
    d.mkdir()
    kind = rng.choice(["json", "bindings", "psl", "space"])
    if kind == "space":
        from fretc.common.errors import FretcError
        from fretc.sim.space import load_space

        p = _space(rng, d)
        try:
            load_space(p)
        except FretcError as exc:
            return [] if str(p) in str(exc) or p.name in str(exc) else [
                f"space error does not name the file: {exc}"]
        return []
    args = {"json": lambda: _fret_json(rng, d / "r.json"), "bindings": lambda: _bindings(rng, d),
            "psl": lambda: _psl_map(rng, d)}[kind]()
    res = CliRunner().invoke(main, args)
    out = res.output
    if res.exit_code not in (0, 1, 2, 3):
        return [f"{kind}: exit {res.exit_code}: {out[-400:]!r} {res.exception!r}"]
    if "internal error" in out or "Traceback" in out:
        return [f"{kind}: {out[-400:]!r}"]
    return []
