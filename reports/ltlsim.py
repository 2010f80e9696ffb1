"""``fretc ltlsim``: FRET's simulator (LTLSIM) as a page served on this machine. The user edits
a trace of the requirements' variables (booleans toggled per tick, numbers typed; ticks added
and removed) and sees, per requirement, its value at each tick, FRET's verdict of the trace
and the first violation.

Design notes: ARCHITECTURE.md, `reports/ltlsim.py`."""

from __future__ import annotations

import json
import math
import re
import socket
import sys
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any
from urllib.parse import urlsplit

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
                             f"got {_brief(values[bad])}")
        return np.array(values, dtype=np.bool_)
    out = np.empty(n, dtype=np.float64)
    for i, v in enumerate(values):
        x = _finite(v)
        if x is None:
            raise TraceError(f"variable {name!r} at tick {i}: a finite number expected, "
                             f"got {_brief(v)}")
        out[i] = x
    return out


def _finite(v: Any) -> float | None:
    """``v`` as a finite double, None when it is not a number (a boolean is not) or is
    none (NaN, an infinity, an integer past the doubles' range: JSON's integers have no
    bound, RFC 8259 section 6)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    try:
        x = float(v)
    except OverflowError:
        return None
    return x if math.isfinite(x) else None


def _brief(v: Any) -> str:
    """A short, safe showing of a posted JSON value in an error message: its kind for an
    array or an object (whose repr could be long or nested past the recursion limit), the
    first characters of a string, the digit count of a long integer."""
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "an object"
    if isinstance(v, str):
        return repr(v[:40]) + ("..." if len(v) > 40 else "")
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 10 ** 30:
        return f"an integer of {len(str(abs(v)))} digits"
    return json.dumps(v)


def _columns(variables: list[dict], trace: Any) -> tuple[dict[str, np.ndarray], int]:
    """The columns of a posted trace (module docstring for its shape)."""
    if not isinstance(trace, dict):
        raise TraceError('the trace is not a JSON object {"ticks": n, "values": {...}}')
    n = trace.get("ticks")
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_TICKS:
        raise TraceError(f'"ticks": a whole number from 1 to {MAX_TICKS} expected, got '
                         f'{_brief(n)}')
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
    with ``serve_forever()``. What it answers: the module docstring.

    Raises:
        OSError: the port cannot be bound.
    """
    return _Server(("127.0.0.1", port), compiled, ticks)


class _Server(ThreadingHTTPServer):
    """The simulator's server: the page and the requirements' JSON made once, the
    requirements judged per request (:class:`_Handler`)."""

    def __init__(self, address: tuple[str, int], compiled: list, ticks: int):
        self.compiled = compiled
        self.page = page_html().encode("utf-8")
        self.meta = json.dumps(_requirements_json(compiled, ticks)).encode("utf-8")
        super().__init__(address, _Handler)

    def own_origins(self) -> tuple[str, str]:
        """The page's own origins as served: ``http://127.0.0.1:PORT``, ``http://localhost:
        PORT``."""
        port = self.server_address[1]
        return f"http://127.0.0.1:{port}", f"http://localhost:{port}"

    def shutdown_request(self, request: Any) -> None:
        """Close a connection once answered, reading first (at most :data:`MAX_BODY` bytes
        more, for at most a second) what the client still sends: a body refused unread
        would otherwise make the close a reset, which can lose the answer on its way."""
        try:
            request.shutdown(socket.SHUT_WR)
            request.settimeout(1.0)
            left = MAX_BODY + 65536
            while left > 0:
                chunk = request.recv(65536)
                if not chunk:
                    break
                left -= len(chunk)
        except OSError:
            pass
        self.close_request(request)

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A request that failed past the handler's own answers: a client gone (its
        connection reset, timed out) is nothing to report; anything else is one line on
        stderr, never a traceback."""
        exc = sys.exc_info()[1]
        if isinstance(exc, (ConnectionError, TimeoutError)):
            return
        sys.stderr.write(f"fretc ltlsim: a request failed: {type(exc).__name__}: {exc}\n")


class _Refused(Exception):
    """A request answered with the 4xx ``status`` and the JSON ``{"error": message}``."""

    def __init__(self, status: int, message: str, headers: tuple[tuple[str, str], ...] = ()):
        super().__init__(message)
        self.status, self.message, self.headers = status, message, headers


#: the hosts a request may name (the server listens on 127.0.0.1 only)
_HOSTS = ("127.0.0.1", "localhost")


class _Handler(BaseHTTPRequestHandler):
    """One request: ``GET /`` (the page), ``GET /api/requirements``, ``POST /api/judge``;
    anything else, or a request of another host or origin, a 4xx with a JSON error."""

    server: _Server
    server_version = "fretc-ltlsim"
    timeout = 10  # seconds a read or write on the connection may wait (a client stalled)

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - quiet
        return

    def _send(self, code: int, body: bytes, kind: str,
              headers: tuple[tuple[str, str], ...] = ()) -> None:
        self.send_response(code)
        self.send_header("Content-Type", kind)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "same-origin")
        self.send_header("Content-Security-Policy", "default-src 'self'; "
                         "script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                         "frame-ancestors 'none'; form-action 'none'; base-uri 'none'")
        for name, value in headers:
            self.send_header(name, value)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, code: int, value: Any, headers: tuple[tuple[str, str], ...] = ()) -> None:
        self._send(code, json.dumps(value).encode("utf-8"), "application/json", headers)

    def send_error(self, code: int, message: str | None = None,
                   explain: str | None = None) -> None:
        """http.server's own refusals (a request line or headers it cannot read, a method
        with no handler) as this server's: JSON, and 4xx (a method other than GET and POST
        405, an HTTP version it does not speak 400)."""
        extra: tuple[tuple[str, str], ...] = ()
        if code == HTTPStatus.NOT_IMPLEMENTED:
            code, extra = HTTPStatus.METHOD_NOT_ALLOWED, (("Allow", "GET, POST"),)
            message = "only GET and POST are served"
        elif code >= 500:
            code = HTTPStatus.BAD_REQUEST
        if self.request_version == "HTTP/0.9":  # (else no status line would be written)
            self.request_version = "HTTP/1.0"
        self.close_connection = True
        self._json(code, {"error": message or HTTPStatus(code).phrase}, extra)

    def parse_request(self) -> bool:
        """http.server's reading of the request line and headers; an HTTP/0.9 request
        (no version: its answer would have no status line) is refused."""
        if not super().parse_request():
            return False
        if self.request_version == "HTTP/0.9":
            self.send_error(HTTPStatus.BAD_REQUEST, "HTTP/1.0 or HTTP/1.1 expected")
            return False
        return True

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        self._answer(post=False)

    def do_POST(self) -> None:  # noqa: N802 - http.server's name
        self._answer(post=True)

    def _answer(self, post: bool) -> None:
        try:
            _check_host(self.headers.get_all("Host") or [], self.server.server_address[1])
            _check_origin(self.headers, self.server.own_origins(), post)
            path = self.path.split("?", 1)[0]
            if post and path == "/api/judge":
                trace = _read_json(self.headers, self.rfile)
                with np.errstate(all="ignore"):
                    answer = judge_trace(self.server.compiled, trace)
                self._send(200, json.dumps(answer).encode("utf-8"), "application/json")
            elif not post and path in ("/", "/index.html"):
                self._send(200, self.server.page, "text/html; charset=utf-8")
            elif not post and path == "/api/requirements":
                self._send(200, self.server.meta, "application/json")
            else:
                raise _Refused(404, "not found")
        except _Refused as r:
            self.close_connection = True
            self._json(r.status, {"error": r.message}, r.headers)
        except TraceError as exc:
            self._json(400, {"error": str(exc)})
        except (ConnectionError, TimeoutError):
            raise  # (the client is gone: nothing to answer)
        except Exception as exc:  # a fault of fretc's, not of the request: said, not hidden
            sys.stderr.write(f"fretc ltlsim: internal error on {self.command} {self.path[:80]}"
                             f": {type(exc).__name__}: {exc}\n")
            self._json(500, {"error": f"internal error: {type(exc).__name__}: {exc}"})


def _check_host(hosts: list[str], port: int) -> None:
    """Raise :class:`_Refused` (403) unless the request names one ``Host``, 127.0.0.1 or
    localhost (with no port or ``port``): a page of another site reaching the server
    through DNS rebinding names its own host."""
    if len(hosts) == 1:
        host, _, given = hosts[0].strip().lower().partition(":")
        if host in _HOSTS and given in ("", str(port)):
            return
    raise _Refused(403, "only 127.0.0.1 or localhost")


def _origin(value: str) -> str | None:
    """The origin ``scheme://host:port`` of an ``Origin`` header's value or a ``Referer``
    URL (port 80 when an http URL gives none); None when it has none (``null``, not a
    URL)."""
    try:
        parts = urlsplit(value.strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme.lower() != "http" or not parts.hostname:
        return None
    return f"http://{parts.hostname.lower()}:{port if port is not None else 80}"


def _check_origin(headers: Any, own: tuple[str, ...], post: bool) -> None:
    """Raise :class:`_Refused` (403) for a request of another origin: the ``Origin`` header
    judged when present (one, naming one of ``own``), else the ``Referer``'s origin; a POST
    must carry one of them (browsers send ``Origin`` with every POST, same-origin fetches
    included: the Fetch standard, "append a request Origin header")."""
    for name in ("Origin", "Referer"):
        given = headers.get_all(name) or []
        if not given:
            continue
        if len(given) == 1 and _origin(given[0]) in own:
            return
        raise _Refused(403, f"a request of another origin ({name}): only the page's own, "
                            f"{' or '.join(own)}")
    if post:
        raise _Refused(403, "a POST must carry an Origin (or Referer) header naming the "
                            f"page's own origin, {' or '.join(own)}")


#: JSON media types a POST may declare (RFC 8259 section 11; parameters such as charset
#: are read past)
_JSON_TYPES = ("application/json",)


def _read_json(headers: Any, rfile: Any) -> Any:
    """The JSON body of a POST; :class:`_Refused` when it cannot be read: 411 without a
    ``Content-Length`` (or with a ``Transfer-Encoding``, not read here), 400 for a length
    that is not one byte count, a body shorter than it, not UTF-8 or not JSON (nested past
    the reader's recursion limit included), 413 for one over :data:`MAX_BODY`, 415 for a
    ``Content-Type`` other than JSON."""
    if headers.get_all("Transfer-Encoding"):
        raise _Refused(411, "a body with a Transfer-Encoding is not read: send a "
                            "Content-Length")
    lengths = [x.strip() for x in headers.get_all("Content-Length") or []]
    if not lengths:
        raise _Refused(411, "a Content-Length is required")
    if len(set(lengths)) != 1 or not re.fullmatch(r"[0-9]{1,15}", lengths[0]):
        raise _Refused(400, f"Content-Length: one byte count expected, got "
                            f"{', '.join(lengths)[:40]!r}")
    size = int(lengths[0])
    if not 0 < size <= MAX_BODY:
        raise _Refused(413 if size else 400, f"a body of 1 to {MAX_BODY} bytes expected, "
                                             f"Content-Length says {size}")
    media = (headers.get("Content-Type") or "").split(";", 1)[0].strip().lower()
    if media not in _JSON_TYPES:
        raise _Refused(415, f"Content-Type: application/json expected, got {media[:40]!r}")
    raw = rfile.read(size)
    if len(raw) < size:
        raise _Refused(400, f"the body ended after {len(raw)} of the {size} bytes its "
                            "Content-Length says")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _Refused(400, f"the body is not UTF-8 (byte {exc.start})") from None
    try:
        return json.loads(text)
    except RecursionError:
        raise _Refused(400, "the body is not JSON: nested too deeply") from None
    except ValueError as exc:
        raise _Refused(400, f"the body is not JSON: {exc}") from None
