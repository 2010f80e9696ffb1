"""The documentation's promises that do not need MkDocs: the README is a short front page
whose links resolve, the command reference covers every command and option, the version has
one source, and neither the docs nor the code's comments cite tracker issues.

(``mkdocs build --strict``, which fails on broken links inside the site, runs in CI:
``.ci/run``.)
"""
from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
#: the packages of the library, the benchmarks and the tests: their comments and docstrings
CODE_FOLDERS = ("common", "fretish", "compiler", "check", "monitors", "fretc", "sim",
                "templates", "bench", "tests", "qualification")
#: a tracker reference ("issue 9", "(issue", "issue #4") or an instruction count
ISSUE = re.compile(r"[Ii]ssue #?\d|\(issue|\binstructions\b")


def _commands_hook():
    spec = importlib.util.spec_from_file_location("docs_commands_hook",
                                                  ROOT / "docs" / "hooks" / "commands.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_readme_is_a_short_front_page_with_the_two_commands_first():
    text = README.read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150
    blocks = re.findall(r"^    (python3 -m venv .*)$", text, re.M)
    assert blocks[0].endswith("fretc audit --requirements requirements/ traces/")
    assert blocks[1].endswith(".venv/bin/python -m pytest")
    assert "../shared is absent" in text


def test_readme_links_resolve():
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text)
    assert len(links) > 20
    missing = [ln for ln in links if "://" not in ln and not (ROOT / ln).exists()]
    assert not missing


def test_command_reference_has_every_command_and_option():
    from fretc.cli import main

    page = _commands_hook().on_page_markdown("# Commands\n\n<!-- fretc-commands -->\n",
                                             None, None, None)
    ctx = click.Context(main, info_name="fretc")
    names = main.list_commands(ctx)
    assert {"audit", "check", "compile", "inspect", "report", "watch", "replay"} <= set(names)
    for name in names:
        cmd = main.get_command(ctx, name)
        assert f"## `fretc {name}`" in page
        for param in cmd.params:
            if isinstance(param, click.Option):
                assert param.opts[0] in page, (name, param.opts)
    assert "| `-r, --requirements PATH` |" in page
    assert "<!-- fretc-commands -->" not in page


def test_version_has_one_source():
    """``fretc --version`` prints the version pyproject.toml sets (via the installed
    package's metadata), and no module spells a version of its own."""
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    out = subprocess.run([str(Path(sys.executable).parent / "fretc"), "--version"],
                         capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0
    assert out.stdout.strip() == f"fretc, version {version}"
    assert f"## [{version}]" in (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")


def test_no_issue_numbers_in_docs_or_code_comments():
    """Pages and comments speak of the code, not of the tracker (or of instruction counts)."""
    files = [README, ROOT / "ARCHITECTURE.md", *sorted((ROOT / "docs").rglob("*.md"))]
    for folder in CODE_FOLDERS:
        files += sorted((ROOT / folder).rglob("*.py"))
    hits = []
    for path in files:
        if path.resolve() == Path(__file__).resolve():
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if ISSUE.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits[:40])


def test_python_api_examples_run():
    # every ```python block of the Python API page, in order, from the top of the clone: the
    # page's imports are the installed names (fretc.*), and what it asserts holds
    page = (ROOT / "docs" / "reference" / "python-api.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", page, re.M | re.S)
    assert len(blocks) >= 2 and all("from fretc." in b for b in blocks)
    proc = subprocess.run([sys.executable, "-c", "\n".join(blocks)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "(G (too_close -> (F stopped)))" in proc.stdout
