"""`fretc watch` with no server to connect to says so at once, naming the URL and the
reason, then keeps counting its attempts (a status, never silence), as a client of the
ecosystem does (`ros2 topic echo`, Foxglove)."""

from __future__ import annotations

import pytest

pytest.importorskip("websockets", reason="websockets is not installed: pip install 'fretc[watch]'")

from click.testing import CliRunner  # noqa: E402

from fretc.audit import AuditConfig, load_plan  # noqa: E402
from fretc.cli import main  # noqa: E402
from fretc.cli.watch import connection_line  # noqa: E402
from fretc.live.watch import Watch, WatchOptions  # noqa: E402
from fretc.live.watch_event import WatchEvent  # noqa: E402

from _bus import free_port, write_watch_files  # noqa: E402

pytestmark = pytest.mark.watch


def test_no_server_is_an_event_at_the_first_failed_attempt(tmp_path):
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n",
                             'a_ok = "/a.data > 0"\n')
    plan = load_plan(AuditConfig(requirements=(str(fret),)))
    url = f"ws://127.0.0.1:{free_port()}"
    w = Watch(plan, WatchOptions(url=url, duration=1.5, backoff=0.05, max_backoff=0.2))
    la = w.run()
    tries = [e for e in w.events if e.kind == "unreachable"]
    assert tries and tries[0].extra["attempts"] == 1, [e.kind for e in w.events]
    assert url in tries[0].detail and "refused" in tries[0].detail.lower(), tries[0].detail
    assert [e.extra["attempts"] for e in tries] == list(range(1, len(tries) + 1))
    assert "could not connect" in (la.error or "")


def test_the_command_prints_the_url_and_reason_then_a_count(tmp_path):
    fret = write_watch_files(tmp_path, "RA: the robot shall always satisfy a_ok\n",
                             'a_ok = "/a.data > 0"\n')
    url = f"ws://127.0.0.1:{free_port()}"
    res = CliRunner().invoke(main, ["watch", url, "-r", str(fret), "--no-live",
                                    "--duration", "1.5"])
    first = [line for line in res.stderr.splitlines() if line.startswith("fretc watch: cannot")]
    assert len(first) == 1 and url in first[0] and "retrying" in first[0], res.stderr
    assert res.exit_code == 2, res.output  # (no connection: nothing could be watched)


def test_the_count_is_said_at_powers_of_two():
    def line(n: int) -> str | None:
        return connection_line(WatchEvent("unreachable", None, 0, detail="cannot connect to "
                                          "ws://h:1: refused", extra={"attempts": n}), None)

    said = [n for n in range(1, 70) if line(n) is not None]
    assert said == [1, 2, 4, 8, 16, 32, 64]
    assert "--connect-timeout" in line(1) and "after 8 attempts" in line(8)
    assert connection_line(WatchEvent("pt"), 5.0) is None
