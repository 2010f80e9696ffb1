"""Fleet audits (audit/fleet/ray.py): ``--ray`` gives the ``-j 1`` JSON; faults give error
entries, never verdicts; ``--retries`` recovers a lost worker; log lists.

The tests marked ``ray`` share one local Ray (2 CPUs) for the module (Ray starts slowly);
without Ray installed they are skipped. Deselect them with ``-m 'not ray'``.
"""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import pytest
from click.testing import CliRunner

from fretc.cli import main
from fretc.audit.fleet import ray as fleet
from fretc.audit import discovery
from fretc.audit import AuditConfig, AuditInputError, audit_log, audit_logs, load_plan
from fretc.audit.verdict import audit_json, exit_code

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "logs"  # needs the shared fixture
TRACES = [str(p) for p in sorted((ROOT / "traces").glob("*.mcap"))]
REAL = ROOT / "requirements" / "real_logs"


def _doc(plan, results) -> str:
    input_errors = any(r.error is not None for r in plan.requirements)
    return audit_json(results, plan.requirements_json(), plan.bindings_json(), input_errors)


@pytest.fixture(scope="module")
def safe_ros():
    return load_plan(AuditConfig(requirements=(str(ROOT / "requirements"),)))


@pytest.fixture(scope="module")
def local_docs(safe_ros):
    """-j 1 results of the shipped traces (the reference)."""
    return audit_logs(safe_ros, TRACES, jobs=1)


@pytest.fixture(scope="module")
def ray_session():
    ray = pytest.importorskip("ray")
    started = fleet.connect(num_cpus=2)
    yield ray
    if started:
        ray.shutdown()


# --------------------------------------------------------------------------- on Ray
@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_ray_json_equals_local_on_traces_and_real_logs(shared, ray_session, safe_ros, local_docs):
    got = fleet.audit_logs_ray(safe_ros, TRACES)
    assert _doc(safe_ros, got) == _doc(safe_ros, local_docs)
    for name in ("cmd_vel_scaled", "stage_mapping1"):
        log = next(SHARED.glob(name + ".*"))
        plan = load_plan(AuditConfig(requirements=(str(REAL / f"{name}.fret"),)))
        local = audit_logs(plan, [str(log)], jobs=1)
        assert local[0].ticks_evaluated > 0
        assert _doc(plan, fleet.audit_logs_ray(plan, [str(log)])) == _doc(plan, local)


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_killed_task_gives_an_error_entry_and_the_others_complete(ray_session, safe_ros,
                                                                 local_docs, tmp_path):
    marker = tmp_path / "kill-once"
    marker.touch()
    got = fleet.audit_logs_ray(safe_ros, TRACES, retries=0,
                               _kill=("nominal.mcap", str(marker)))
    assert not marker.exists()  # the worker did die mid-run
    victim = TRACES.index(str(ROOT / "traces" / "nominal.mcap"))
    assert got[victim].error and "lost" in got[victim].error
    assert {v.verdict for v in got[victim].verdicts} == {"error"}
    assert all("log not audited" in v.error for v in got[victim].verdicts)
    for i, (a, b) in enumerate(zip(got, local_docs)):
        if i != victim:
            assert a.to_json() == b.to_json()
    assert exit_code(got) == 2


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_retries_recover_a_lost_worker(ray_session, safe_ros, local_docs, tmp_path):
    marker = tmp_path / "kill-once"
    marker.touch()
    got = fleet.audit_logs_ray(safe_ros, TRACES, retries=1,
                               _kill=("nominal.mcap", str(marker)))
    assert not marker.exists()
    assert _doc(safe_ros, got) == _doc(safe_ros, local_docs)


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_a_task_that_raises_is_an_error_entry(ray_session, safe_ros, local_docs):
    got = fleet.audit_logs_ray(safe_ros, TRACES[:2], _kill=(Path(TRACES[1]).name, ":raise"))
    assert got[0].to_json() == local_docs[0].to_json()
    assert "RuntimeError: fault injected by the tests" in got[1].error
    assert {v.verdict for v in got[1].verdicts} == {"error"}


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_cli_writes_the_json_when_the_raylet_is_killed(tmp_path):
    """As a user runs it: ``fretc audit --ray --json`` in its own process, the raylet killed
    mid-run: exit code 2 (not 1, "violated"), the JSON written, nothing reported satisfied
    that was not audited."""
    import subprocess
    import sys

    marker = tmp_path / "kill-raylet-once"
    marker.write_text("")
    script = (
        "import sys; from fretc.audit.fleet import ray as fleet; real = fleet.audit_logs_ray\n"
        "def hooked(*a, **k):\n"
        f"    k['_kill'] = ('nominal.mcap', ':raylet:{marker}'); k['num_cpus'] = 1\n"
        "    return real(*a, **k)\n"
        "fleet.audit_logs_ray = hooked\n"
        "from fretc.cli import main; sys.exit(main())\n")
    out, local = tmp_path / "ray.json", tmp_path / "local.json"
    args = ["audit", "-r", str(ROOT / "requirements"), *TRACES, "--no-progress", "--json"]
    r = subprocess.run([sys.executable, "-c", script, *args, str(out), "--ray"],
                       capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert not marker.exists(), "the fault was not injected"
    assert r.returncode == 2, r.stdout[-2000:] + r.stderr[-2000:]
    CliRunner().invoke(main, [*args, str(local), "-j", "1"])
    got = json.loads(out.read_text())["logs"]
    want = json.loads(local.read_text())["logs"]
    lost = [la for la in got if la.get("error")]
    kept = [(a, b) for a, b in zip(got, want) if not a.get("error")]
    assert [la["log"] for la in got] == TRACES
    assert len(kept) >= 1 and any(la["log"].endswith("nominal.mcap") for la in lost)
    # what the user gets, not the wording of a race (which of Ray's errors reaches the
    # driver first depends on timing): each lost log has an error entry that says how to
    # retry, and its requirements are errors, never verdicts
    assert all(la["error"].strip() and "--retries" in la["error"] for la in lost), lost
    assert all({v["verdict"] for v in la["verdicts"]} == {"error"} for la in lost)
    assert all(a == b for a, b in kept)
    assert "[state-dump]" not in r.stdout + r.stderr  # Ray's own output stays out


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_cli_ray_equals_cli_local(ray_session, tmp_path):
    runner = CliRunner()
    logs = TRACES[:2]
    args = ["audit", "-r", str(ROOT / "requirements"), *logs, "--no-progress"]
    a = runner.invoke(main, args + ["--json", str(tmp_path / "a.json"), "-j", "1"])
    b = runner.invoke(main, args + ["--json", str(tmp_path / "b.json"), "--ray"])
    assert a.exit_code == b.exit_code and a.exit_code in (0, 1), b.output
    assert (tmp_path / "a.json").read_text() == (tmp_path / "b.json").read_text()


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_report_ray_writes_the_local_audit(ray_session, tmp_path):
    runner = CliRunner()
    args = ["report", "-r", str(ROOT / "requirements"), TRACES[0]]
    a = runner.invoke(main, args + ["-o", str(tmp_path / "a")])
    b = runner.invoke(main, args + ["-o", str(tmp_path / "b"), "--ray"])
    assert a.exit_code == b.exit_code, b.output
    assert (tmp_path / "a" / "audit.json").read_text() == \
           (tmp_path / "b" / "audit.json").read_text()


# --------------------------------------------------------------------------- without Ray
def test_ray_missing_says_how_to_get_it(monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "ray" else real(name, *a))
    r = CliRunner().invoke(main, ["audit", TRACES[0], "--ray"])
    assert r.exit_code == 2
    assert "pip install 'fretc[ray]'" in r.output


def test_ray_address_that_is_a_log_path_is_refused():
    pytest.importorskip("ray")
    r = CliRunner().invoke(main, ["audit", "--ray", "traces/"])
    assert r.exit_code == 2
    assert "not a Ray address" in r.output


def test_shipped_plan_pickles_and_audits_the_same(safe_ros, local_docs):
    shipped = pickle.loads(pickle.dumps(fleet.ship_plan(safe_ros)))
    plan = shipped.rebuild()
    assert [r.monitor_cls.__name__ for r in plan.requirements if r.monitor_cls] == \
           [r.monitor_cls.__name__ for r in safe_ros.requirements if r.monitor_cls]
    assert audit_log(plan, TRACES[1]).to_json() == local_docs[1].to_json()


def test_error_audit_is_never_satisfied(safe_ros):
    la = fleet.error_audit(safe_ros, "x.mcap", "boom")
    assert la.error == "x.mcap: boom"
    assert len(la.verdicts) == len(safe_ros.requirements)
    assert {v.verdict for v in la.verdicts} == {"error"}
    assert exit_code([la]) == 2


def test_log_lists_and_globs(tmp_path):
    (tmp_path / "a").mkdir()
    for n in ("a/1.mcap", "a/2.mcap", "b.mcap"):
        (tmp_path / n).write_bytes(b"")
    lst = tmp_path / "logs.txt"
    lst.write_text("# fleet index\n\na/*.mcap\n  b.mcap  \n" + str(tmp_path / "a/1.mcap") + "\n")
    got = discovery.expand_log_args([f"@{lst}", str(tmp_path / "**" / "2.mcap")])
    assert got == [str(tmp_path / "a/1.mcap"), str(tmp_path / "a/2.mcap"),
                   str(tmp_path / "b.mcap"), str(tmp_path / "a/1.mcap"),
                   str(tmp_path / "a/2.mcap")]
    with pytest.raises(AuditInputError, match=r"logs.txt:1: .*nope\*: no file matches"):
        lst.write_text("nope*\n")
        discovery.expand_log_args([f"@{lst}"])
    with pytest.raises(AuditInputError, match="cannot read the log list"):
        discovery.expand_log_args([f"@{tmp_path / 'missing.txt'}"])


def test_cli_reads_a_log_list(tmp_path):
    lst = tmp_path / "logs.txt"
    lst.write_text("\n".join(TRACES[:2]) + "\n")
    runner = CliRunner()
    base = ["audit", "-r", str(ROOT / "requirements"), "--no-progress", "--json", "-"]
    a = runner.invoke(main, base + [f"@{lst}"])
    b = runner.invoke(main, base + TRACES[:2])
    assert a.exit_code == b.exit_code
    assert json.loads(a.stdout)["logs"] == json.loads(b.stdout)["logs"]


@pytest.mark.ray
@pytest.mark.xdist_group("ray")
def test_local_ray_serves_no_dashboard(ray_session):
    """A local Ray started by fretc (the ``ray_session`` fixture uses :func:`fleet.connect`):
    no process of it listens on the dashboard's port, nor on its agent's HTTP port."""
    psutil = pytest.importorskip("psutil")
    procs = psutil.Process().children(recursive=True)
    import re

    agent_ports = {int(m) for p in procs
                   for m in re.findall(r"--listen-port=(\d+)", " ".join(_cmdline(p)))}
    assert agent_ports, "the agent's HTTP port is not in the raylet's command line"
    listening = set()
    for p in procs:
        try:
            listening |= {c.laddr.port for c in p.net_connections("inet")
                          if c.status == psutil.CONN_LISTEN}
        except psutil.Error:
            continue
    assert listening, "no Ray process found listening at all: the test sees nothing"
    assert 8265 not in listening and not (agent_ports & listening)


def _cmdline(p) -> list[str]:
    try:
        return p.cmdline()
    except Exception:
        return []
