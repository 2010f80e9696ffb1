"""The language server's reading of its standard input, with bounds: LSP's base protocol
(``Content-Length: N`` header lines, an empty line, N bytes of JSON), read so that no message
can make the server allocate without limit, wait on a body that will never come in a form it
cannot leave, or end.

Design notes: ARCHITECTURE.md, `editor/transport.py`."""

from __future__ import annotations

import asyncio
import json
import logging
import re
import sys
import threading
from typing import BinaryIO, TYPE_CHECKING
from collections.abc import AsyncIterator, Callable

if TYPE_CHECKING:
    from pygls.lsp.server import LanguageServer

__all__ = ["serve_stdio", "MAX_HEADER", "MAX_MESSAGE", "read_messages"]

#: the longest header line kept (bytes)
MAX_HEADER = 8192
#: the largest message body read (bytes)
MAX_MESSAGE = 64 << 20

_LENGTH = re.compile(rb"Content-Length:[ \t]*([0-9]{1,20})[ \t]*\r?\n\Z", re.I)
log = logging.getLogger("fretc.editor")


class _Reader:
    """Blocking reads of ``stream`` in the executor (as pygls's stdin reader)."""

    def __init__(self, stream, executor=None):
        self.stream = stream
        self.executor = executor

    async def readline(self) -> bytes:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self.executor, self.stream.readline, MAX_HEADER)

    async def read(self, n: int) -> bytes:
        loop = asyncio.get_running_loop()
        return await loop.run_in_executor(self.executor, self.stream.read, n)


async def read_messages(reader: asyncio.StreamReader,
                        problem: Callable[[str], None] = lambda text: None
                        ) -> AsyncIterator[bytes]:
    """Yield the bodies (bytes) of the well-formed messages read by ``reader`` (``readline``
    of at most :data:`MAX_HEADER` bytes, ``read(n)``), until the end of the input;
    ``problem(text)`` is told of each malformed one (module docstring)."""
    length = None
    while True:
        line = await reader.readline()
        if not line:
            return
        if not line.endswith(b"\n"):  # longer than MAX_HEADER: drop the rest of the line
            while line and not line.endswith(b"\n"):
                line = await reader.readline()
            problem(f"a header line longer than {MAX_HEADER} bytes: dropped")
            length = None
            continue
        m = _LENGTH.match(line)
        if m:
            n = int(m.group(1))
            if n > MAX_MESSAGE:
                problem(f"a message of {n:,} bytes (Content-Length) is over the limit of "
                        f"{MAX_MESSAGE:,}: skipped to the next header")
                length = None
                continue
            length = n
            continue
        if line.lower().startswith(b"content-length"):
            problem(f"a malformed Content-Length header {line[:80]!r}: skipped to the next "
                    "header")
            length = None
            continue
        if line.strip() or length is None:
            continue  # another header (Content-Type), or a line between messages
        body = b""
        while len(body) < length:
            chunk = await reader.read(length - len(body))
            if not chunk:
                return
            body += chunk
        length = None
        yield body


async def _serve(stop: threading.Event, reader, protocol) -> None:
    async for body in read_messages(reader, lambda text: log.warning("fretc lsp: %s", text)):
        if stop.is_set():
            return
        try:
            message = json.loads(body, object_hook=protocol.structure_message)
        except Exception as exc:  # noqa: BLE001 - one bad message never ends the server
            log.warning("fretc lsp: a message that cannot be read was skipped: %s",
                        str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
            _refuse(protocol, body, exc)
            continue
        try:
            protocol.handle_message(message)
        except Exception as exc:  # noqa: BLE001
            log.warning("fretc lsp: a message that cannot be handled was skipped: %s",
                        str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
            _refuse(protocol, body, exc)


def _refuse(protocol, body: bytes, exc: Exception) -> None:
    """Answer a request that could not be read or handled (its parameters of the wrong
    types: pygls cannot structure it, so nothing else answers it) with an error, so the
    client does not wait for ever; a notification or a body without an id gets none."""
    from pygls.exceptions import JsonRpcException, JsonRpcInvalidParams

    try:
        data = json.loads(body)
    except (ValueError, RecursionError):  # not JSON, or nested too deeply to read
        return
    if not isinstance(data, dict) or "method" not in data or \
            not isinstance(data.get("id"), (int, str)) or isinstance(data.get("id"), bool):
        return
    error = exc if isinstance(exc, JsonRpcException) else JsonRpcInvalidParams(
        f"the request could not be read: {type(exc).__name__}")
    try:
        protocol._send_response(data["id"], error=error.to_response_error())
    except Exception:  # noqa: BLE001 - a client gone: nothing to answer
        pass


def serve_stdio(server: LanguageServer, stdin: BinaryIO | None = None,
                stdout: BinaryIO | None = None) -> int:
    """Serve ``server`` (a pygls ``LanguageServer``) over standard input and output until the
    client exits or the input ends (pygls's ``start_io`` with this module's reader); the
    process's exit code: LSP's (``exit``: 0 after ``shutdown``, else 1), 0 at the end of the
    input."""
    from pygls.io_ import StdoutWriter

    server._stop_event = stop = threading.Event()
    reader = _Reader(stdin or sys.stdin.buffer, server.thread_pool)
    server.protocol.set_writer(StdoutWriter(stdout or sys.stdout.buffer))
    code = 0
    try:
        asyncio.run(_serve(stop, reader, server.protocol))
    except BrokenPipeError:
        log.error("fretc lsp: the connection to the client is lost")
    except KeyboardInterrupt:
        pass
    except SystemExit as exc:  # pygls's exit handler: the code LSP gives it
        code = exc.code if isinstance(exc.code, int) else 0
    finally:
        server.shutdown()
    return code
