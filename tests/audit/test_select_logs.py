"""Binding files that select their logs (``[logs]`` glob / topics): one
requirements folder serves several robots and simulators."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from click.testing import CliRunner

from fretc.cli import main

from _shared import SHARED, needs_shared

ROOT = Path(__file__).resolve().parents[2]
REAL = ROOT / "requirements" / "real_logs"
LOGS = SHARED / "data" / "logs"


def _run(*args):
    return CliRunner().invoke(main, ["audit", "--no-progress", *map(str, args)])


@needs_shared
def test_one_requirements_folder_over_both_real_logs(tmp_path):
    """Today: exit 2, "one audit uses one clock"."""
    res = _run("-r", REAL, LOGS / "cmd_vel_scaled.mcap", LOGS / "stage_mapping1.bag",
               "--json", tmp_path / "a.json")
    assert res.exit_code == 1, res.output  # CV2 and ST2 are violated on purpose
    doc = json.loads((tmp_path / "a.json").read_text())
    got = {(Path(la["log"]).name, v["requirement"]): v["verdict"]
           for la in doc["logs"] for v in la["verdicts"]}
    assert got == {("cmd_vel_scaled.mcap", "CV1"): "satisfied",
                   ("cmd_vel_scaled.mcap", "CV2"): "violated",
                   ("cmd_vel_scaled.mcap", "CV3"): "satisfied",
                   ("stage_mapping1.bag", "ST1"): "satisfied",
                   ("stage_mapping1.bag", "ST2"): "violated",
                   ("stage_mapping1.bag", "ST3"): "satisfied"}
    assert doc["summary"]["error"] == 0


def _copy_real(tmp_path, glob_a='"stage_mapping1*.bag"'):
    for f in REAL.iterdir():
        shutil.copy(f, tmp_path / f.name)
    p = tmp_path / "stage_mapping1.bindings.toml"
    p.write_text(p.read_text().replace('glob = "stage_mapping1*.bag"', f"glob = {glob_a}"))


def test_a_log_selected_by_no_binding_file_is_an_input_error_naming_them(tmp_path):
    _copy_real(tmp_path)
    res = _run("-r", tmp_path, ROOT / "traces" / "nominal.mcap")
    assert res.exit_code == 2
    out = " ".join(res.output.split())
    assert "no binding file selects" in out
    assert "cmd_vel_scaled.bindings.toml" in out and "stage_mapping1.bindings.toml" in out


@needs_shared
def test_a_log_selected_by_two_binding_files_is_an_input_error_naming_both(tmp_path):
    _copy_real(tmp_path, glob_a='"*"')
    (tmp_path / "stage_mapping1.bindings.toml").write_text(
        (tmp_path / "stage_mapping1.bindings.toml").read_text()
        .replace('topics = ["/base_scan", "/base_pose_ground_truth"]\n', ""))
    res = _run("-r", tmp_path, LOGS / "cmd_vel_scaled.mcap")
    assert res.exit_code == 2
    out = " ".join(res.output.split())
    assert "selected by both" in out
    assert "cmd_vel_scaled.bindings.toml" in out and "stage_mapping1.bindings.toml" in out


def test_stage_speed_is_the_norm_of_the_planar_twist():
    text = (REAL / "stage_mapping1.bindings.toml").read_text()
    assert "norm(/base_pose_ground_truth.twist.twist.linear.x, " \
           "/base_pose_ground_truth.twist.twist.linear.y)" in text
    assert "takes minutes" not in (REAL / "stage_mapping1.fret").read_text()


@needs_shared
def test_a_plan_with_selecting_binding_files_ships_to_workers():
    """Ray workers get the plan pickled (audit.fleet.ship_plan): the per-file plans go
    along and give the same verdicts."""
    import pickle

    from fretc.audit import AuditConfig, audit_log, load_plan
    from fretc.audit.fleet.ray import ship_plan

    plan = load_plan(AuditConfig(requirements=(str(REAL),)))
    again = pickle.loads(pickle.dumps(ship_plan(plan))).rebuild()
    log = str(LOGS / "cmd_vel_scaled.mcap")
    assert [(v.requirement, v.verdict) for v in audit_log(again, log).verdicts] == \
        [(v.requirement, v.verdict) for v in audit_log(plan, log).verdicts] == \
        [("CV1", "satisfied"), ("CV2", "violated"), ("CV3", "satisfied")]
