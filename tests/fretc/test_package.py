"""fretc installs as one import package, ``fretc``, beside any other distribution.

The wheel is built from this checkout (``python -m build --wheel --no-isolation``: this
environment's setuptools, no download); its files must lie under ``fretc/`` and its
``.dist-info`` only, with the data the code reads (grammars, the template table, Jinja2
templates, the simulator's map and spaces). Installed into a fresh virtual environment beside
a distribution that owns a top-level package whose name is one of the repository's folders
(``editor``, as the ``editor`` distribution that ``inquirer`` depends on), it leaves that
package intact, and ``fretc`` and ``python -m fretc`` run from a folder outside the checkout.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: files the installed code opens by path: each must be inside the wheel
DATA = ("fretc/fretish/grammar.lark", "fretc/signals/bindings/grammar.lark",
        "fretc/templates/monitor_module.py.j2", "fretc/templates/report.html.j2",
        "fretc/sim/data/reactor_room_map.yaml", "fretc/sim/spaces/environment.toml",
        "fretc/compiler/table/after-holding-after-0.json",
        "fretc/qualification/requirements.toml", "fretc/qualification/known_problems.toml")


#: what the wheel is built from: pyproject.toml's package folders and the README it names
SOURCES = ("pyproject.toml", "README.md", "src", "common", "fretish", "compiler", "check",
           "logs", "signals", "monitors", "audit", "testing", "shield", "live", "sim", "reports",
           "editor", "qualification", "templates")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    pytest.importorskip("build", reason="the 'build' package is not installed")
    out = tmp_path_factory.mktemp("wheel")
    src = tmp_path_factory.mktemp("source")  # a copy: the build writes build/ and egg-info
    for name in SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, src / name, symlinks=True,  # src/fretc's links
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        else:
            shutil.copy(ROOT / name, src / name)
    proc = subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation",
                           "--outdir", str(out), str(src)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    (whl,) = out.glob("fretc-*.whl")
    return whl


def test_the_wheel_holds_one_import_package_and_its_data(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names}
    assert {t for t in tops if not t.endswith(".dist-info")} == {"fretc"}, sorted(tops)
    (info,) = [t for t in tops if t.endswith(".dist-info")]
    top_level = zipfile.ZipFile(wheel).read(f"{info}/top_level.txt").decode().split()
    assert top_level == ["fretc"]
    missing = [d for d in DATA if d not in names]
    assert not missing, missing
    # every source module is in it, as fretc.<folder>...
    for folder in ("common", "fretish", "compiler", "check", "logs", "signals", "monitors",
                   "audit", "testing", "shield", "live", "sim", "reports", "editor",
                   "qualification"):
        for p in (ROOT / folder).rglob("*.py"):
            assert f"fretc/{p.relative_to(ROOT).as_posix()}" in names, p
    assert "fretc/cli/__init__.py" in names and "fretc/__main__.py" in names


def _editor_wheel(folder: Path) -> Path:
    """A wheel of a distribution ``editor`` 9.9 whose package ``editor`` has ``edit``: the
    shape of PyPI's ``editor`` (a dependency of ``inquirer``), made here so the test needs no
    download."""
    dist = "editor-9.9.dist-info"
    files = {"editor/__init__.py": "def edit(*args, **kwargs):\n    return 'edited'\n",
             f"{dist}/METADATA": "Metadata-Version: 2.1\nName: editor\nVersion: 9.9\n",
             f"{dist}/WHEEL": "Wheel-Version: 1.0\nGenerator: test\nRoot-Is-Purelib: true\n"
                              "Tag: py3-none-any\n",
             f"{dist}/top_level.txt": "editor\n"}
    files[f"{dist}/RECORD"] = "".join(f"{n},,\n" for n in files) + f"{dist}/RECORD,,\n"
    path = folder / "editor-9.9-py3-none-any.whl"
    with zipfile.ZipFile(path, "w") as z:
        for name, text in files.items():
            z.writestr(name, text)
    return path


def _venv_beside_this_one(folder: Path) -> Path:
    """A fresh virtual environment that sees this one's site-packages as a plain path (its
    dependencies: Spot, numpy, ...) but not its ``.pth`` files (not this checkout's editable
    install of fretc); returns its python."""
    venv.EnvBuilder(with_pip=False).create(folder)
    python = folder / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; "
                           "print(sysconfig.get_paths()['purelib'])"], capture_output=True,
                          text=True, check=True).stdout.strip()
    Path(site, "_fretc_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return python


def _pip_install(python: Path, wheel: Path) -> None:
    # this environment's pip installs into the new one (it has none of its own)
    proc = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install",
                           "-q", "--no-deps", "--no-index", str(wheel)], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_installed_beside_another_editor_package_both_work(wheel, tmp_path):
    python = _venv_beside_this_one(tmp_path / "env")
    _pip_install(python, _editor_wheel(tmp_path))
    _pip_install(python, wheel)
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    probe = subprocess.run([str(python), "-c", "import editor, fretc.editor, fretc.cli; "
                            "print(editor.edit(), editor.__file__, fretc.cli.__file__)"],
                           cwd=outside, env=env, capture_output=True, text=True, timeout=120)
    assert probe.returncode == 0, probe.stderr
    edited, editor_file, cli_file = probe.stdout.split()
    assert edited == "edited" and str(ROOT) not in editor_file and str(ROOT) not in cli_file
    reqs = ROOT / "requirements"
    audit = subprocess.run([str(tmp_path / "env" / "bin" / "fretc"), "audit", "-r", str(reqs),
                            str(ROOT / "traces" / "stop_delay.mcap"), "--no-progress",
                            "--json", "-"], cwd=outside, env=env, capture_output=True,
                           text=True, timeout=600)
    assert audit.returncode == 1, audit.stderr[-3000:]
    # the same verdicts, evidence and robustness as this checkout's own fretc gives
    here = subprocess.run([sys.executable, "-m", "fretc", "audit", "-r", str(reqs),
                           str(ROOT / "traces" / "stop_delay.mcap"), "--no-progress", "--json",
                           "-"], cwd=outside, capture_output=True, text=True, timeout=600)
    assert json.loads(audit.stdout)["logs"] == json.loads(here.stdout)["logs"]
    verdicts = {v["requirement"]: v["verdict"] for v in json.loads(audit.stdout)["logs"][0]
                ["verdicts"]}
    assert verdicts["R2"] == "violated"
    version = subprocess.run([str(python), "-m", "fretc", "--version"], cwd=outside, env=env,
                             capture_output=True, text=True, timeout=120)
    assert version.returncode == 0 and "fretc" in version.stdout


def test_run_from_the_clone_the_installed_package_is_found(wheel, tmp_path):
    # the README's `pip install .`, then commands run from the clone's top (where the tour
    # runs): nothing there is named fretc, so the installed package answers, all of it
    python = _venv_beside_this_one(tmp_path / "env")
    _pip_install(python, wheel)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    for args in (["-m", "fretc", "--version"], ["-m", "fretc.sim", "serve", "--help"],
                 ["-c", "import fretc.testing.generate, fretc.shield, fretc.check.distinguish"]):
        proc = subprocess.run([str(python), *args], cwd=ROOT, env=env, capture_output=True,
                              text=True, timeout=120)
        assert proc.returncode == 0, (args, proc.stderr[-2000:])
    where = subprocess.run([str(python), "-c", "import fretc.cli; print(fretc.cli.__file__)"],
                           cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert str(tmp_path / "env") in where.stdout, where.stdout


@pytest.mark.tor("TOR-QUA-001")
def test_qualify_passes_on_a_fresh_install(wheel, tmp_path):
    # the kit's validation suite on the wheel installed into a fresh environment, run from a
    # folder outside the checkout: it needs nothing of the clone (its tests, its data)
    python = _venv_beside_this_one(tmp_path / "env")
    _pip_install(python, wheel)
    (tmp_path / "home").mkdir()
    env = {k: v for k, v in os.environ.items()
           if k != "PYTHONPATH" and not k.startswith(("XDG_", "FRETC_"))}
    env["HOME"] = str(tmp_path / "home")
    proc = subprocess.run([str(python), "-m", "fretc", "qualify", "-o", str(tmp_path / "kit")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    doc = json.loads((tmp_path / "kit" / "report.json").read_text(encoding="utf-8"))
    assert doc["result"] == "passed" and all(m["killed"] for m in doc["mutants"])
    assert doc["environment"]["python"]["executable"].startswith(str(tmp_path / "env"))

