"""The scaffolding the middleware tests share (DDS, Zenoh, and the Foxglove WebSocket where a
test runs all three): a URL on 127.0.0.1 of this worker's own, the replay and the watch as
the user runs them (each `fretc` in a process of its own), a publisher of fretc's own
servers stepped by the test in a thread while `fretc watch` runs in the test's process, and
the audit of the same log to compare with."""

from __future__ import annotations

import json
import os
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from click.testing import CliRunner, Result

from fretc.cli import main

from _dds import fresh_domain

ROOT = Path(__file__).resolve().parents[2]
#: the shipped Safe-ROS requirements
REQS = str(ROOT / "requirements")
#: a std_msgs/Float64 channel: encoding, type, schema encoding, schema
FLOAT64 = ("cdr", "std_msgs/msg/Float64", "ros2msg", b"float64 data")
#: a date in 2023 (ns): the first log time of the tests' own messages
T0 = 1_700_000_000 * 10**9


def free_port() -> int:
    """A TCP port on 127.0.0.1 nothing listens on (now)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def bus_url(transport: str) -> str:
    """A URL of ``transport`` (``dds``, ``zenoh``, ``ws``) no other test uses: a DDS domain of
    this worker's own (:func:`_dds.fresh_domain`), a free port for Zenoh and WebSocket."""
    if transport == "dds":
        return f"dds://{fresh_domain()}"
    if transport == "ws":
        return f"ws://127.0.0.1:{free_port()}"
    return f"zenoh://127.0.0.1:{free_port()}"


def bus_config(url: str, dds_xml: str) -> list[str]:
    """The options a DDS URL needs on 127.0.0.1 (the loopback configuration); none else."""
    return ["--dds-config", dds_xml] if url.startswith("dds://") else []


def fretc_cmd(*args: str) -> list[str]:
    """``python -m fretc ARGS`` with this interpreter."""
    return [sys.executable, "-m", "fretc", *args]


def fretc_env() -> dict[str, str]:
    """The environment of a fretc process: the clone's own ``src/`` first on the path (the
    tests then run the code of the tree they belong to, not another installed copy)."""
    return {**os.environ, "PYTHONPATH": str(ROOT / "src")}


def float64_cdr(x: float) -> bytes:
    """A std_msgs/Float64 ``x`` as CDR (little-endian encapsulation)."""
    return b"\x00\x01\x00\x00" + struct.pack("<d", x)


def write_watch_files(folder: Path, requirements: str, variables: str,
                      tables: str = "") -> Path:
    """``folder/w.fret`` (``@tick_period 100 ms`` then ``requirements``) and its bindings
    beside it (a 100 ms tick on log time, ``[variables]`` then ``tables``); the .fret path."""
    fret = folder / "w.fret"
    fret.write_text("@tick_period 100 ms\n" + requirements, encoding="utf-8")
    (folder / "w.bindings.toml").write_text(
        '[tick]\nperiod = "100 ms"\ntime = "log"\n[variables]\n' + variables + tables,
        encoding="utf-8")
    return fret


def bus_server(url: str, dds_xml: str, channels: Sequence[str] = (),
               channel: tuple = FLOAT64) -> Any:
    """fretc's own publisher on ``url`` (a :class:`fretc.live.dds.serve.DdsServer` or a
    :class:`fretc.live.zenoh.serve.ZenohServer`) with ``channel`` (default Float64) on each
    of ``channels``."""
    if url.startswith("dds://"):
        from fretc.live.dds.serve import DdsServer

        server = DdsServer(url, dds_xml)
    else:
        from fretc.live.zenoh.serve import ZenohServer

        server = ZenohServer(url)
    for topic in channels:
        server.channel(topic, *channel)
    return server


def watch_while(publish: Callable[[], None], url: str, fret: Path, dds_xml: str = "",
                *extra: str, duration: float = 30, wait: float | None = 10,
                grace: float = 1, join: float = 20) -> tuple[Result, dict]:
    """``fretc watch URL -r FRET --json`` in this process while ``publish`` runs in a thread
    (it ends the run: its server stops); (the command's result, the watched log's JSON)."""
    t = threading.Thread(target=publish, daemon=True)
    t.start()
    out = fret.parent / "w.json"
    args = ["watch", url, "-r", str(fret), "--no-live", "--json", str(out),
            "--duration", str(duration), "--restart-grace", str(grace)]
    if wait is not None:
        args += ["--wait", str(wait)]
    res = CliRunner().invoke(main, args + bus_config(url, dds_xml) + list(extra))
    t.join(join)
    assert out.exists(), res.output
    return res, json.loads(out.read_text())["logs"][0]


def replay(trace: Path | str, url: str, dds_xml: str, rate: str = "30",
           *extra: str, quiet: bool = False) -> subprocess.Popen:
    """``fretc replay TRACE --serve URL --rate RATE`` in a process of its own (stdout and
    stderr piped, or dropped with ``quiet``)."""
    pipe = subprocess.DEVNULL if quiet else subprocess.PIPE
    serve = (["--serve", "--port", url.rsplit(":", 1)[1]] if url.startswith("ws://")
             else ["--serve", url, *bus_config(url, dds_xml)])
    return subprocess.Popen(fretc_cmd("replay", str(trace), *serve, "--rate", rate, *extra),
                            cwd=ROOT, stdout=pipe, stderr=pipe, env=fretc_env())


def watch_process(url: str, reqs: Sequence[str], out: Path, dds_xml: str, *extra: str,
                  wait: str = "10", duration: str = "120", timeout: float = 150
                  ) -> subprocess.CompletedProcess:
    """``fretc watch URL REQS --json OUT`` in a process of its own, to its end."""
    return subprocess.run(fretc_cmd("watch", url, *reqs, "--json", str(out), "--no-live",
                                    "--wait", wait, "--duration", duration,
                                    *bus_config(url, dds_xml), *extra),
                          cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          env=fretc_env())


def audit_json(log: Path | str, out: Path, reqs: Sequence[str] = ("-r", REQS)
               ) -> tuple[int, dict]:
    """``fretc audit REQS LOG --json OUT``: (exit code, the JSON)."""
    res = CliRunner().invoke(main, ["audit", *reqs, str(log), "--json", str(out)])
    return res.exit_code, json.loads(out.read_text())


def verdicts(doc: dict) -> list[tuple]:
    """(requirement, verdict, first violation, robustness) of every verdict of a JSON."""
    return [(v["requirement"], v["verdict"], v.get("first_violation"), v.get("robustness"))
            for log in doc["logs"] for v in log["verdicts"]]
