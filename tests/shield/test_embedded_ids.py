"""Ids and texts from a FRET export embedded in generated code stay data (hostile
round 9, J1), each finding from its smallest input, then a property test of hostile ids per
form.

* A requirement id holding a line break, or Java's six characters ``\\u000a``, was written raw
  into a ``//`` comment of ``N_shield.java``: the code after it ran when the class loaded
  (Java translates ``\\uXXXX`` anywhere in the source before lexing, JLS 17, section 3.3).
* The ``.jpf`` file ``fretc ajpf`` writes is a Java properties file: a ``.psl`` label ending
  in ``\\`` continued its line; a path with ``#``, ``=``, spaces is data too.
* ``fretc ajpf --java bin/java`` (a relative path) was an internal error (JPF runs in the
  agent's folder).
* A requirement id too long for a file name left part of the Gwendolen files written.

Every form escapes every id with :mod:`fretc.common.textsafe`'s function for its language;
the property test generates each form for hostile ids, compiles and loads it (Python always;
C with gcc, Java with javac, or a skip naming the missing compiler) and checks that no
injected code runs and that the id reads back where the form shows it.
"""

from __future__ import annotations

import codecs
import json
import os
import re
import shutil
import stat
import subprocess
import types
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from fretc.cli import main
from fretc.common.errors import FretcError
from fretc.common.textsafe import (java_comment, java_string, properties_key, properties_value,
                                   python_doc)
from fretc.compiler.build import compile_entries
from fretc.fretish.files import load_requirements
from fretc.shield.ajpf_run import AjpfRunError, psl_labels
from fretc.shield.build import build_shield
from fretc.shield.emit_c import render_c
from fretc.shield.emit_gwendolen import render_gwendolen
from fretc.shield.emit_python import render_python

JAVAC, JAVA = shutil.which("javac"), shutil.which("java")
GCC = shutil.which("gcc") or shutil.which("cc")
NO_JAVA = "no javac and java on the PATH: the Java forms are not compiled here"
NO_CC = "no C compiler (gcc, cc) on the PATH: the C form is not compiled here"

#: the findings' payloads: each prints PWNED when the Java (or C, or Python) around it runs it
PAYLOADS = ['R1\n}static{System.out.println("PWNED");}//',
            'R2\\u000a}static{System.out.println("PWNED");}//',
            'R3\\u000d}static{System.out.println("PWNED");}//',
            'R4\\uu000a}static{System.out.println("PWNED");}//',
            'R5 */ int pwned = puts("PWNED"); /*',
            'R6"""\nprint("PWNED")\n"""',
            'R7\\', 'R8 \u202e\u2028\x85 x', 'R9 #=:! \\u0022', "R10 ??/\n#define x"]
#: Java's unicode escape, where the compiler translates it (JLS 3.3: an even number of
#: backslashes before it)
_JAVA_ESCAPE = re.compile(r"(?<!\\)((?:\\\\)*)\\u+([0-9a-fA-F]{4})")


def _java_translated(source: str) -> str:
    """``source`` after Java's unicode pre-translation (JLS 3.3)."""
    return _JAVA_ESCAPE.sub(lambda m: m.group(1) + chr(int(m.group(2), 16)), source)


def _shield(tmp: Path, ids: list[str], name: str = "hostile"):
    reqs = [{"reqid": rid, "fulltext": f"whenever a sw shall immediately satisfy x{k % 2}"}
            for k, rid in enumerate(ids)]
    path = tmp / "r.json"
    path.write_text(json.dumps(reqs), encoding="utf-8")
    compiled = compile_entries(load_requirements([path]))
    return build_shield(compiled, ["a"], ["x0", "x1"], fork=False, name=name), compiled


# ------------------------------------------------------------------ the escaping functions
_HOSTILE_TEXT = st.text(st.sampled_from(list("ab\\u0Aa\"'*/?#=:! \n\r\t\x00{};$,")
                                        + ["\u202e", "\u2028", "\x85", "\ud800", "\U0001f600",
                                           "\xe9"]), max_size=24)


@settings(max_examples=300)
@given(_HOSTILE_TEXT)
def test_java_comment_is_one_ascii_line_with_no_unicode_escape_and_reads_back(text):
    c = java_comment(text)
    assert c.isascii() and c.isprintable()
    assert _java_translated(c) == c  # (nothing Java would translate)
    assert codecs.decode(c.encode("ascii"), "unicode_escape") == text


@settings(max_examples=300)
@given(_HOSTILE_TEXT)
def test_java_string_is_one_ascii_literal_whose_translation_has_no_break(text):
    lit = java_string(text)
    assert lit.isascii() and lit.isprintable()
    body = _java_translated(lit)[1:-1]
    assert "\n" not in body and "\r" not in body
    assert re.fullmatch(r'(?:[^"\\]|\\.)*', body, re.S)  # (no quote ends it early)


@settings(max_examples=300)
@given(_HOSTILE_TEXT)
@pytest.mark.tor("TOR-GEN-005")
def test_python_doc_reads_back_in_a_docstring(text):
    doc = python_doc(text)
    source = f'"""{doc}"""\n'
    source.encode("utf-8")  # (no lone surrogate left: the file can be written)
    tree = compile(source, "<doc>", "exec", dont_inherit=True, flags=0x400)  # PyCF_ONLY_AST
    assert len(tree.body) == 1 and tree.body[0].value.value == text


# ------------------------------------------------------------------ the findings' inputs
@pytest.mark.tor("TOR-GEN-005")
def test_j1_a_line_break_or_java_escape_in_an_id_runs_no_java(tmp_path):
    """The finding: the Gwendolen form's ``N_shield.java`` compiled and loaded runs no
    injected code, and its comment reads back as the ids."""
    if not (JAVAC and JAVA):
        pytest.skip(NO_JAVA)
    ids = PAYLOADS[:4]
    shield, compiled = _shield(tmp_path, ids)
    files = render_gwendolen(shield, compiled, "hostile")
    _check_gwendolen(files, tmp_path / "java", [r.id for r in shield.requirements])


def test_j1_a_psl_label_ending_in_a_backslash_is_refused_naming_its_line(tmp_path):
    psl = tmp_path / "a.psl"
    psl.write_text("# c\nok_1: [] B(a,x)\nbad\\: [] B(a,x)\n", encoding="utf-8")
    with pytest.raises(AjpfRunError) as err:
        psl_labels(psl)
    assert f"{psl}:3: the property label 'bad" in str(err.value)


def _fake_tools(tmp_path: Path) -> None:
    """A fake MCAPL folder and fake ``java``/``javac`` in ``tmp_path`` (``bin/``): the java
    keeps the files JPF is given in ``tmp_path/got`` and reports no errors."""
    mcapl = tmp_path / "mcapl"
    (mcapl / "lib" / "3rdparty").mkdir(parents=True)
    (mcapl / "lib" / "3rdparty" / "RunJPF.jar").write_bytes(b"")
    (mcapl / "bin" / "ail" / "util").mkdir(parents=True)
    (mcapl / "bin" / "ail" / "util" / "AJPF_w_AIL.class").write_bytes(b"")
    (tmp_path / "bin").mkdir()
    (tmp_path / "got").mkdir()
    java = tmp_path / "bin" / "java"
    java.write_text(f"""#!/bin/sh
if [ "$1" = "-version" ]; then echo 'openjdk version "11.0.2"' >&2; exit 0; fi
cp "$4" '{tmp_path}/got/check.jpf'
cp "${{3#+site=}}" '{tmp_path}/got/site.properties'
printf ' results\\nno errors detected\\n statistics\\nstates: new=1\\n'
""", encoding="utf-8")
    javac = tmp_path / "bin" / "javac"
    javac.write_text('#!/bin/sh\nif [ "$1" = "-version" ]; then echo "javac 17"; fi\nexit 0\n',
                     encoding="utf-8")
    for f in (java, javac):
        f.chmod(f.stat().st_mode | stat.S_IXUSR)


@pytest.mark.skipif(os.name != "posix", reason="the fake java is a POSIX shell script")
def test_j1_ajpf_with_a_relative_java_runs_and_writes_a_jpf_that_reads_back(tmp_path,
                                                                         monkeypatch):
    """``fretc ajpf 'ag b#c=d!' --java bin/java --javac bin/javac --mcapl mcapl``, all
    relative: the run ends (exit 0, the property holds), and the ``.jpf`` JPF was given reads
    back (``java.util.Properties``, where Java is here) as the agent's absolute paths and
    the label."""
    _fake_tools(tmp_path)
    agent = tmp_path / "ag b#c=d!"
    agent.mkdir()
    for name, text in (("r.gwen", "GWENDOLEN\n"), ("r.psl", "R1: [] B(a,x)\n"),
                       ("r.ail", "mas.file = r.gwen\n"), ("r_env.java", ""),
                       ("r_shield.java", "")):
        (agent / name).write_text(text, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    got = CliRunner().invoke(main, ["ajpf", agent.name, "--mcapl", "mcapl", "--java",
                                    "bin/java", "--javac", "bin/javac"])
    assert got.exit_code == 0, got.output + repr(got.exception)
    assert "R1: holds" in got.output
    if not (JAVAC and JAVA):
        pytest.skip(NO_JAVA + " (the .jpf is not read back)")
    jpf, site = _load_properties(tmp_path / "props",
                                 [tmp_path / "got" / "check.jpf",
                                  tmp_path / "got" / "site.properties"])
    assert jpf["target.args"] == f"{agent / 'r.ail'},{agent / 'r.psl'},R1"
    assert site["mcapl"] == str((tmp_path / "mcapl").resolve())


def test_j1_an_id_too_long_for_a_file_name_writes_nothing(tmp_path):
    reqs = [{"reqid": "R" + "x" * 300, "fulltext": "whenever a sw shall immediately satisfy x"}]
    (tmp_path / "r.json").write_text(json.dumps(reqs), encoding="utf-8")
    out = tmp_path / "out"
    got = CliRunner().invoke(main, ["shield", str(tmp_path / "r.json"), "--inputs", "a",
                                    "--outputs", "x", "--emit", "gwendolen", "-o", str(out)])
    assert got.exit_code == 2, got.output
    assert "file name of" in got.output and "nothing was written" in got.output
    assert not out.exists()


def test_j1_the_ros2_package_xml_and_init_keep_hostile_ids_data(tmp_path):
    """The ROS 2 package's ``package.xml`` (ids in its description) parses with one
    description and no element an id adds; its ``__init__`` docstring reads back."""
    import xml.etree.ElementTree as ET

    from fretc.shield import emit_ros2

    ids = ['R1</description><exec_depend>evil</exec_depend><description>', "R2 & <!--"]
    shield, _c = _shield(tmp_path, ids, name='n"""\nimport os #')
    xml = emit_ros2._package_xml("p", shield, ["rclpy"])
    root = ET.fromstring(xml.split("\n", 2)[2])
    assert [e.text for e in root.iter("exec_depend")] == ["rclpy"]
    assert all(rid in root.find("description").text for rid in ids)


# ------------------------------------------------------------------ helpers per form
def _load_properties(folder: Path, files: list[Path]) -> list[dict[str, str]]:
    """Each of ``files`` as ``java.util.Properties.load`` reads it (UTF-8)."""
    folder.mkdir(exist_ok=True)
    src = folder / "LoadProps.java"
    src.write_text("""import java.io.*; import java.util.*;
public class LoadProps {
  static String j(String s) { StringBuilder b = new StringBuilder("\\"");
    for (char c : s.toCharArray()) b.append(String.format("\\\\u%04x", (int) c));
    return b.append("\\"").toString(); }
  public static void main(String[] a) throws Exception {
    for (String f : a) { Properties p = new Properties();
      try (Reader r = new InputStreamReader(new FileInputStream(f), "UTF-8")) { p.load(r); }
      StringBuilder b = new StringBuilder("{");
      for (String k : new TreeSet<>(p.stringPropertyNames()))
        b.append(b.length() > 1 ? "," : "").append(j(k)).append(":").append(j(p.getProperty(k)));
      System.out.println(b.append("}")); } } }
""", encoding="utf-8")
    if not (folder / "LoadProps.class").exists():
        subprocess.run([JAVAC, "-d", str(folder), str(src)], check=True, timeout=300)
    got = subprocess.run([JAVA, "-cp", str(folder), "LoadProps", *map(str, files)],
                         capture_output=True, text=True, check=True, timeout=300)
    return [json.loads(line) for line in got.stdout.splitlines()]


def _check_gwendolen(files: dict[str, str], folder: Path, ids: list[str]) -> None:
    """The Java class compiled and loaded (no PWNED), its comment read back as ``ids``; the
    environment's comments all comments after Java's translation; the ``.gwen`` header and
    the ``.psl`` lines of their shapes; every ``.ail`` read by ``Properties`` with only
    the keys fretc writes."""
    folder.mkdir(exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    (shield_java,) = [n for n in files if n.endswith("_shield.java")]
    got = subprocess.run([JAVAC, "-encoding", "UTF-8", "-d", str(folder),
                          str(folder / shield_java)], capture_output=True, text=True,
                         timeout=300)
    assert got.returncode == 0, got.stderr
    run = subprocess.run([JAVA, "-cp", str(folder), shield_java[:-5]], input="",
                         capture_output=True, text=True, timeout=300)
    assert "PWNED" not in run.stdout + run.stderr
    text = files[shield_java]
    assert text.isascii()
    (line,) = [x for x in text.splitlines() if x.startswith("// Requirements enforced: ")]
    shown = line[len("// Requirements enforced: "):-1]
    assert shown == ", ".join(java_comment(i) for i in ids)
    assert codecs.decode(shown.encode(), "unicode_escape") == ", ".join(ids)
    (env_java,) = [n for n in files if n.endswith("_env.java")]
    head = _java_translated(files[env_java]).split("\nimport ", 1)[0]
    assert all(x.startswith("//") for x in head.splitlines()), head
    (gwen,) = [n for n in files if n.endswith(".gwen")]
    head = files[gwen].split("\nGWENDOLEN\n", 1)[0]
    assert all(x.startswith("//") for x in head.splitlines()), head
    (psl,) = [n for n in files if n.endswith(".psl")]
    for x in files[psl].splitlines():
        assert x.startswith("#") or re.match(r"[A-Za-z0-9_]+: ", x), x
    ails = sorted(n for n in files if n.endswith(".ail"))
    known = {"mas.file", "mas.builder", "env", "ajpf.transition_every_reasoning_cycle",
             "log.warning", "log.format", "hostile_env.inputs", "hostile_env.proposals"}
    for props in _load_properties(folder / "props", [folder / n for n in ails]):
        assert set(props) <= known, props
        assert props["mas.file"] == "hostile.gwen"


def _check_python(text: str, ids: list[str], tmp: Path) -> None:
    text.encode("utf-8")  # (the module can be written)
    marker = tmp / "PWNED"
    mod = types.ModuleType("hostile_shield")
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        exec(compile(text, "<hostile>", "exec"), mod.__dict__)
    finally:
        os.chdir(cwd)
    assert not marker.exists()
    assert list(mod.REQUIREMENTS) == ids
    assert all(f"  {rid} (" in mod.__doc__ for rid in ids)


def _check_c(files: dict[str, str], ids: list[str], folder: Path) -> None:
    folder.mkdir(exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text, encoding="utf-8")
    (folder / "t.c").write_text(f"""#include <stdio.h>
#include "hostile_shield.h"
int main(void) {{
    size_t r, k;
    for (r = 0; r < {len(ids)}u; r++) {{
        const char *s = HOSTILE_SHIELD_REQUIREMENT_IDS[r];
        for (k = 0; s[k]; k++) printf("%02x", (unsigned char)s[k]);
        printf("\\n");
    }}
    return 0;
}}
""", encoding="utf-8")
    got = subprocess.run([GCC, "-std=c99", "-pedantic", "-Wall", "-Werror", "-o",
                          str(folder / "t"), str(folder / "t.c"),
                          str(folder / "hostile_shield.c"), "-lm"],
                         capture_output=True, text=True, timeout=300)
    assert got.returncode == 0, got.stderr
    run = subprocess.run([str(folder / "t")], capture_output=True, text=True, timeout=60)
    assert "PWNED" not in run.stdout
    assert run.stdout.split() == [i.encode("utf-8", "surrogatepass").hex() for i in ids]


# ------------------------------------------------------------------ the property test
_IDS = st.lists(st.one_of(st.sampled_from(PAYLOADS),
                          st.text(st.sampled_from(list("Rab\\u0Aa\"*/?#=:! \n\r{};")
                                                  + ["\u202e", "\u2028", "\xe9"]),
                                  min_size=1, max_size=16)),
                min_size=1, max_size=3, unique=True)


@pytest.mark.slow
@settings(max_examples=8, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(_IDS)
def test_hostile_ids_stay_data_in_every_form(tmp_path_factory, ids):
    """For hostile ids (the findings' payloads, and text of line breaks, quotes, backslashes,
    ``u``, hex digits, comment marks, bidirectional controls), each form generated, compiled
    and loaded: Python (exec: no marker file, ``REQUIREMENTS`` and the docstring read back),
    C (gcc ``-Werror``: the ids' bytes read back), Java (javac, the class loaded: no PWNED,
    the comment reads back; the ``.ail`` files read by ``Properties``)."""
    tmp = tmp_path_factory.mktemp("ids")
    try:
        shield, compiled = _shield(tmp, ids)
    except FretcError:
        assume(False)  # (an id the loader refuses, with its reason: nothing generated)
    shown = [r.id for r in shield.requirements]
    _check_python(render_python(shield), shown, tmp)
    if GCC:
        _check_c(render_c(shield, "hostile"), shown, tmp / "c")
    if JAVAC and JAVA:
        _check_gwendolen(render_gwendolen(shield, compiled, "hostile"), tmp / "java", shown)
    if not (GCC and JAVAC and JAVA):
        pytest.skip(" and ".join(r for r, ok in ((NO_CC, GCC), (NO_JAVA, JAVAC and JAVA))
                                 if not ok))


def test_properties_escapes_read_back_in_java(tmp_path):
    """:func:`properties_key` and :func:`properties_value` of hostile texts read back by
    ``java.util.Properties.load`` exactly (a trailing ``\\``, ``=``, ``:``, ``#``, ``!``,
    leading spaces, ``\\u0022``, line breaks)."""
    if not (JAVAC and JAVA):
        pytest.skip(NO_JAVA)
    texts = ["a\\", " lead", "k=v:w#x!y", "\\u0022", "x\ny\rz", "\u202e\U0001f600", "t\t\f"]
    lines = [f"{properties_key('k' + str(i) + t)} = {properties_value(t)}"
             for i, t in enumerate(texts)]
    (tmp_path / "p.properties").write_text("\n".join(lines) + "\n", encoding="utf-8")
    (props,) = _load_properties(tmp_path / "props", [tmp_path / "p.properties"])
    assert props == {f"k{i}{t}": t for i, t in enumerate(texts)}
