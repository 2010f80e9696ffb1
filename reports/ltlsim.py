"""``fretc ltlsim``: FRET's simulator (LTLSIM) as a page served on this machine. The user edits
a trace of the requirements' variables (booleans toggled per tick, numbers typed; ticks added
and removed) and sees, per requirement, its value at each tick, FRET's verdict of the trace
and the first violation.

The trace is judged by the audit's own judge (:func:`fretc.monitors.judge.judge`: FRET's
interval semantics, its evidence and first violation; the pt formula over the columns where
the interval semantics cannot decide), on columns built as the audit builds them from a CSV
trace (a boolean column for a boolean variable, a float column for a number). The value at
tick ``i`` is the pt formula over ticks ``0..i`` (:func:`fretc.monitors.vectorized.pt_series`:
what the generated runtime monitor says at that tick, the verdict of the trace cut there).

The page (``templates/ltlsim.html``: static HTML and JavaScript, no external asset) asks the
server for the requirements (``GET /api/requirements``) and posts the trace as JSON
(``POST /api/judge``, body ``{"ticks": n, "values": {variable: [value per tick]}}``). The
server (:func:`make_server`, the standard library's ``http.server``) listens on 127.0.0.1
only and answers only requests whose ``Host`` is that address or ``localhost`` (a page of
another site cannot reach it through DNS rebinding).
"""

from __future__ import annotations

import json
import math
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

import numpy as np

from fretc.fretish import ast as A
from fretc.fretish.fret_since import SINCE

__all__ = ["MAX_TICKS", "MAX_BODY", "TraceError", "variables_of", "judge_trace",
           "make_server", "page_html"]

#: The longest trace the page may post (ticks), and the largest request body (bytes).
MAX_TICKS = 5000
MAX_BODY = 2_000_000


class TraceError(ValueError):
    """A posted trace that cannot be judged; the message names the variable and tick."""


def _numeric_in(e: A.Expr | None, out: set[str]) -> None:
    """Add to ``out`` the variables ``e`` compares or computes with (numbers)."""
    if e is None:
        return
    for node in A.walk(e):
        if isinstance(node, A.Binary) and node.op in A.COMPARISON_OPS + A.ARITH_OPS:
            out.update(x.name for x in (node.left, node.right) if isinstance(x, A.Var))
        elif isinstance(node, A.Unary) and node.op == "-" and isinstance(node.operand, A.Var):
            out.add(node.operand.name)
        elif isinstance(node, A.Call) and node.name not in ("persisted", "occurred",
                                                            "persists", "occurs", "prevOcc",
                                                            "nextOcc", "preBool", SINCE):
            out.update(x.name for x in node.args if isinstance(x, A.Var))


def variables_of(compiled: list) -> list[dict]:
    """The variables the formalized requirements of ``compiled``
    (:class:`fretc.compiler.build.Compiled`) read, in first-use order:
    ``[{"name", "type"}]``, ``type`` ``"number"`` for a variable compared or computed with,
    else ``"boolean"``."""
    names: list[str] = []
    numeric: set[str] = set()
    for c in compiled:
        f, req = c.formalization, c.requirement
        if f is None or req is None:
            continue
        names += [v for v in f.variables if v not in names]
        for e in (req.scope.mode, req.condition.expr, req.timing.stop, req.response):
            _numeric_in(e, numeric)
    return [{"name": n, "type": "number" if n in numeric else "boolean"} for n in names]


def _column(name: str, kind: str, values: Any, n: int) -> np.ndarray:
    """One posted variable as the audit's column; :class:`TraceError` naming it and the
    tick when a value is not a boolean (booleans) or a finite number (numbers)."""
    if not isinstance(values, list) or len(values) != n:
        raise TraceError(f"variable {name!r}: {n} values expected (one per tick)")
    if kind == "boolean":
        bad = next((i for i, v in enumerate(values) if not isinstance(v, bool)), None)
        if bad is not None:
            raise TraceError(f"variable {name!r} at tick {bad}: true or false expected, "
                             f"got {values[bad]!r}")
        return np.array(values, dtype=np.bool_)
    out = np.empty(n, dtype=np.float64)
    for i, v in enumerate(values):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise TraceError(f"variable {name!r} at tick {i}: a finite number expected, "
                             f"got {v!r}")
        out[i] = float(v)
    return out


def _columns(variables: list[dict], trace: Any) -> tuple[dict[str, np.ndarray], int]:
    """The columns of a posted trace (module docstring for its shape)."""
    if not isinstance(trace, dict):
        raise TraceError('the trace is not a JSON object {"ticks": n, "values": {...}}')
    n = trace.get("ticks")
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_TICKS:
        raise TraceError(f'"ticks": a whole number from 1 to {MAX_TICKS} expected, got {n!r}')
    values = trace.get("values")
    if not isinstance(values, dict):
        raise TraceError('"values": an object {variable: [value per tick]} expected')
    cols = {}
    for v in variables:
        if v["name"] not in values:
            raise TraceError(f"variable {v['name']!r}: missing from the trace")
        cols[v["name"]] = _column(v["name"], v["type"], values[v["name"]], n)
    return cols, n


def _judged(c, cols: dict[str, np.ndarray], n: int) -> dict:
    """One requirement's answer on the columns: its verdict, value per tick, first
    violation (the audit's judge and evidence)."""
    from fretc.monitors.interval import EvidenceUnsupported
    from fretc.monitors.judge import judge
    from fretc.monitors.vectorized import VectorizeError, pt_series

    f, req = c.formalization, c.requirement
    out: dict[str, Any] = {"id": c.id, "text": c.text, "key": f.key, "verdict": "unknown",
                           "values": None, "first_violation": None, "note": None}
    try:
        j = judge(req, f, cols, n)
    except EvidenceUnsupported as exc:
        out["note"] = f"not decided: {exc}"
        return out
    ev = j.evidence
    out["verdict"] = ("violated" if not j.holds else
                      "vacuous" if ev is not None and ev.vacuous else "satisfied")
    out["engine"] = j.engine
    if ev is not None and ev.violation is not None:
        v = ev.violation
        out["first_violation"] = {"tick": v.violation_tick, "trigger": v.trigger_tick,
                                  "interval": list(v.interval), "window": list(v.window),
                                  "reason": v.reason}
    if ev is not None:
        out["triggers"], out["failed"] = ev.triggers, ev.violations
    try:
        out["values"] = [bool(x) for x in pt_series(f.pt, cols, n)]
    except (VectorizeError, KeyError) as exc:
        out["note"] = f"no value per tick: {exc}"
    return out


def judge_trace(compiled: list, trace: Any) -> dict:
    """Judge a posted trace against the requirements of ``compiled``.

    Args:
        compiled: :class:`fretc.compiler.build.Compiled` requirements.
        trace: the JSON object posted (module docstring).

    Returns:
        ``{"ticks": n, "requirements": [{"id", "text", "key", "verdict" ("satisfied",
        "vacuous", "violated", "unknown"), "values" (bool per tick, or None),
        "first_violation" ({"tick", "trigger", "interval", "window", "reason"} or None),
        "note", ...}]}``; a requirement that did not formalize has verdict ``"error"`` and
        its error as ``note``.

    Raises:
        TraceError: the trace is malformed (the message names the variable and tick).
    """
    cols, n = _columns(variables_of(compiled), trace)
    reqs = []
    for c in compiled:
        if c.formalization is None or c.requirement is None:
            reqs.append({"id": c.id, "text": c.text, "key": None, "verdict": "error",
                         "values": None, "first_violation": None,
                         "note": str(c.error) if c.error else "free-form: not formalized"})
            continue
        reqs.append(_judged(c, cols, n))
    return {"ticks": n, "requirements": reqs}


def page_html() -> str:
    """The simulator page (``templates/ltlsim.html``), as served."""
    return resources.files("fretc.templates").joinpath("ltlsim.html").read_text("utf-8")


def _requirements_json(compiled: list, ticks: int) -> dict:
    return {"ticks": ticks, "variables": variables_of(compiled),
            "requirements": [{"id": c.id, "text": c.text,
                              "key": c.formalization.key if c.formalization else None}
                             for c in compiled]}


def make_server(compiled: list, port: int = 0, ticks: int = 12) -> ThreadingHTTPServer:
    """The simulator's HTTP server on 127.0.0.1:``port`` (0: a free port; the bound one is
    ``server.server_address[1]``); ``ticks`` the length of the page's first trace. Serve it
    with ``serve_forever()``.

    Raises:
        OSError: the port cannot be bound.
    """
    page = page_html().encode("utf-8")
    meta = json.dumps(_requirements_json(compiled, ticks)).encode("utf-8")

    class Handler(BaseHTTPRequestHandler):
        server_version = "fretc-ltlsim"

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - quiet
            return

        def _send(self, code: int, body: bytes, kind: str) -> None:
            self.send_response(code)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.send_header("Content-Security-Policy", "default-src 'self'; "
                             "script-src 'unsafe-inline'; style-src 'unsafe-inline'")
            self.end_headers()
            self.wfile.write(body)

        def _local(self) -> bool:
            host = (self.headers.get("Host") or "").rsplit(":", 1)[0]
            if host in ("127.0.0.1", "localhost"):
                return True
            self._send(403, b'{"error": "only 127.0.0.1 or localhost"}', "application/json")
            return False

        def do_GET(self) -> None:  # noqa: N802 - http.server's name
            if not self._local():
                return
            path = self.path.split("?", 1)[0]
            if path in ("/", "/index.html"):
                self._send(200, page, "text/html; charset=utf-8")
            elif path == "/api/requirements":
                self._send(200, meta, "application/json")
            else:
                self._send(404, b'{"error": "not found"}', "application/json")

        def do_POST(self) -> None:  # noqa: N802 - http.server's name
            if not self._local():
                return
            if self.path != "/api/judge":
                self._send(404, b'{"error": "not found"}', "application/json")
                return
            size = int(self.headers.get("Content-Length") or 0)
            if not 0 < size <= MAX_BODY:
                self._send(413, json.dumps({"error": f"a body of 1 to {MAX_BODY} bytes "
                                            "expected"}).encode(), "application/json")
                return
            try:
                answer = judge_trace(compiled, json.loads(self.rfile.read(size)))
            except (TraceError, ValueError) as exc:
                self._send(400, json.dumps({"error": str(exc)}).encode(), "application/json")
                return
            self._send(200, json.dumps(answer).encode("utf-8"), "application/json")

    return ThreadingHTTPServer(("127.0.0.1", port), Handler)
