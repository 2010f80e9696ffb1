"""``fretc ajpf DIR``: AJPF (the model checker of MCAPL, Dennis et al., "Practical verification
of decision-making in agent-based autonomous systems", ASE 2016) run on the agent that ``fretc
shield --emit gwendolen`` wrote into DIR (:mod:`fretc.shield.emit_gwendolen`).

Design notes: ARCHITECTURE.md, `shield/ajpf_run.py`."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from fretc.common.errors import FretcError
from fretc.common.textsafe import properties_value

__all__ = ["AjpfRunError", "Tools", "Verdict", "find_tools", "agent_in", "psl_labels",
           "compile_agent", "check_property", "check_agent"]


class AjpfRunError(FretcError):
    """What ``fretc ajpf`` cannot run: a tool missing or of the wrong version, a folder
    without the agent's files; the message names it and what to do."""


@dataclass(frozen=True)
class Tools:
    """``mcapl`` the MCAPL folder, ``java`` a Java 11 runtime, ``javac`` a Java compiler."""

    mcapl: Path
    java: str
    javac: str


@dataclass(frozen=True)
class Verdict:
    """One property's result: ``verdict`` ``holds``, ``violated`` or ``error``; ``states`` JPF's
    ``states:`` line; ``seconds`` the run's wall time; ``detail`` the reason of an error or the
    length of a violation's accepting path."""

    label: str
    verdict: str
    states: str
    seconds: float
    detail: str = ""


def _major(version_text: str) -> int | None:
    """The major version in ``java -version``'s text (``"11.0.13"`` -> 11, ``"1.8.0"`` -> 8)."""
    m = re.search(r'version "(\d+)(?:\.(\d+))?', version_text) or re.search(
        r"(?:javac|openjdk|java) (\d+)(?:\.(\d+))?", version_text)
    if m is None:
        return None
    major = int(m.group(1))
    return int(m.group(2) or 0) if major == 1 else major


def _version(tool: str, flag: str) -> int | None:
    try:
        got = subprocess.run([tool, flag], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    return _major(got.stdout + got.stderr)


def find_tools(mcapl: str | None, java: str | None, javac: str | None,
               environ: Mapping[str, str] | None = None) -> Tools:
    """The tools (module docstring), from the options, else the environment variables, else
    the ``PATH``.

    Raises:
        AjpfRunError: MCAPL not found or not built, no Java 11 runtime, no javac."""
    env = os.environ if environ is None else environ
    folder = mcapl or env.get("AJPF_HOME")
    if not folder:
        raise AjpfRunError(
            "MCAPL is not given: --mcapl DIR or AJPF_HOME naming the MCAPL folder (git clone "
            "https://github.com/mcapl/mcapl, then ant compile in it)")
    root = Path(os.path.abspath(folder))  # (JPF runs in the agent's folder: never relative)
    jar = root / "lib" / "3rdparty" / "RunJPF.jar"
    main = root / "bin" / "ail" / "util" / "AJPF_w_AIL.class"
    if not jar.is_file() or not main.is_file():
        missing = jar if not jar.is_file() else main
        raise AjpfRunError(f"{folder} is not a built MCAPL folder: {missing} is missing "
                           "(MCAPL's classes are built into bin/ by ant compile)")
    runtime = _program(java or env.get("AJPF_JAVA") or shutil.which("java"))
    if not runtime:
        raise AjpfRunError("no Java runtime: --java PATH or AJPF_JAVA naming a Java 11 java")
    major = _version(runtime, "-version")
    if major is None:
        raise AjpfRunError(f"{runtime} -version did not run or named no version: give a Java 11 "
                           "runtime with --java PATH or AJPF_JAVA")
    if major != 11:
        raise AjpfRunError(
            f"{runtime} is Java {major}: MCAPL's "
            "JPF (v8, jpf-core's Java 11 branch) runs on a Java 11 runtime; give one with "
            "--java PATH or AJPF_JAVA")
    compiler = _program(javac or shutil.which("javac"))
    if not compiler:
        raise AjpfRunError("no javac (JDK 11 or later): --javac PATH")
    cmajor = _version(compiler, "-version")
    if cmajor is None:
        raise AjpfRunError(f"{compiler} -version did not run or named no version: give a javac "
                           "of JDK 11 or later with --javac PATH")
    if cmajor < 11:
        raise AjpfRunError(f"{compiler} is javac {cmajor}: the agent's environment is compiled "
                           "with --release 11, which needs JDK 11 or later (--javac PATH)")
    return Tools(root, runtime, compiler)


def _program(tool: str | None) -> str | None:
    """``tool`` as a command that runs from any folder: a path (it names a folder: ``bin/java``,
    ``./java``) made absolute against the current folder (JPF runs in the agent's folder, so a
    relative one would name another file there, or none), a bare name as the ``PATH``
    finds it (itself when it does not)."""
    if not tool:
        return tool
    if os.sep in tool or (os.altsep is not None and os.altsep in tool):
        return os.path.abspath(tool)
    return shutil.which(tool) or tool


def agent_in(folder: Path) -> str:
    """The stem ``N`` of the agent's files in ``folder`` (``N.gwen``, ``N.psl``, ``N.ail``,
    ``N_env.java``, ``N_shield.java``).

    Raises:
        AjpfRunError: none, or several, or one of the files missing."""
    stems = sorted(p.stem for p in folder.glob("*.gwen"))
    if len(stems) != 1:
        raise AjpfRunError(f"{folder}: " + ("no .gwen file: write the agent with fretc shield "
                                            "... --emit gwendolen -o DIR" if not stems else
                                            f"several agents ({', '.join(stems)}): one a folder"))
    base = stems[0]
    for name in (f"{base}.psl", f"{base}.ail", f"{base}_env.java", f"{base}_shield.java"):
        if not (folder / name).is_file():
            raise AjpfRunError(f"{folder / name} is missing: write the agent again with fretc "
                               "shield ... --emit gwendolen")
    return base


#: a property label fretc writes (:func:`fretc.compiler.ajpf.psl_label`) and passes to JPF
_LABEL = re.compile(r"[A-Za-z0-9_]+")


def psl_labels(psl: Path) -> list[str]:
    """The property labels of a ``.psl`` file, in order (AJPF's reader: a line not starting
    with ``#``, ``label: formula``).

    Raises:
        AjpfRunError: a label that is not letters, digits and ``_`` (as fretc writes them),
            named with its line: it goes into JPF's ``.jpf`` file and a file name, where a
            trailing ``\\`` continues the line and ``,`` splits the target's arguments."""
    from fretc.common.textsafe import one_line

    out = []
    for n, line in enumerate(psl.read_text(encoding="utf-8").splitlines(), 1):
        if line.strip() and not line.startswith("#") and ":" in line:
            label = line.split(":", 1)[0].strip()
            if not _LABEL.fullmatch(label):
                raise AjpfRunError(f"{psl}:{n}: the property label {one_line(repr(label))} is "
                                   "not letters, digits and '_' (as fretc shield writes them): "
                                   "rename it")
            out.append(label)
    return out


def _classpath(mcapl: Path) -> list[str]:
    lib = mcapl / "lib" / "3rdparty"
    return [str(mcapl / "bin"), *sorted(str(p) for p in lib.glob("*.jar"))]


def compile_agent(tools: Tools, folder: Path, base: str, classes: Path) -> None:
    """Compile ``N_env.java`` and ``N_shield.java`` into ``classes``.

    Raises:
        AjpfRunError: javac failed (its messages)."""
    classes.mkdir(parents=True, exist_ok=True)
    got = subprocess.run([tools.javac, "--release", "11", "-nowarn", "-encoding", "UTF-8",
                          "-d", str(classes), "-cp", os.pathsep.join(_classpath(tools.mcapl)),
                          str(folder / f"{base}_env.java"), str(folder / f"{base}_shield.java")],
                         capture_output=True, text=True, timeout=600)
    if got.returncode != 0:
        raise AjpfRunError(f"javac could not compile the agent's environment in {folder}:\n"
                           + (got.stderr or got.stdout)[-2000:])


def check_property(tools: Tools, folder: Path, base: str, label: str, classes: Path,
                   timeout: float = 1800) -> Verdict:
    """Model-check property ``label`` of ``N.psl`` on the agent (module docstring)."""
    scoped = folder / f"{base}_{label}.ail"
    ail = scoped if scoped.is_file() else folder / f"{base}.ail"
    with tempfile.TemporaryDirectory(prefix="fretc-ajpf-") as tmp:
        site, jpf = Path(tmp) / "site.properties", Path(tmp) / "check.jpf"
        # (JPF's files are Java properties files: every path and the label escaped as
        # Properties.store escapes them, textsafe; a path with JPF's list separators is
        # refused before, by _jpf_path)
        site.write_text(f"mcapl = {properties_value(_jpf_path(tools.mcapl.resolve()))}\n",
                        encoding="utf-8")
        extra = ";".join([_jpf_path(classes.resolve()),
                          *map(_jpf_path, _classpath(tools.mcapl)[1:])])
        args = ",".join([_jpf_path(ail.resolve()),
                         _jpf_path((folder / f"{base}.psl").resolve()), label])
        jpf.write_text("\n".join([
            "@using = mcapl", "target = ail.util.AJPF_w_AIL",
            f"target.args = {properties_value(args)}",
            f"classpath+=;{properties_value(extra)}",
            f"native_classpath+=;{properties_value(extra)}", ""]), encoding="utf-8")
        start = time.monotonic()
        try:
            got = subprocess.run(
                [tools.java, "-jar", str(tools.mcapl / "lib" / "3rdparty" / "RunJPF.jar"),
                 f"+site={site}", str(jpf)], cwd=folder, capture_output=True, text=True,
                timeout=timeout, env={**os.environ, "AJPF_HOME": str(tools.mcapl.resolve())})
        except subprocess.TimeoutExpired:
            return Verdict(label, "error", "?", time.monotonic() - start,
                           f"timeout after {timeout:g} s")
        seconds = time.monotonic() - start
    return _verdict(label, got.stdout + got.stderr, seconds)


def _jpf_path(path: Path | str) -> str:
    """``path`` as text for JPF's ``.jpf`` lists.

    Raises:
        AjpfRunError: a path holding ``,`` or ``;`` (JPF splits its lists there) or ``${``
            (JPF expands it), named: move the folder."""
    from fretc.common.textsafe import one_line

    text = str(path)
    if "," in text or ";" in text or "${" in text:
        raise AjpfRunError(f"{one_line(text)}: JPF cannot be given a path holding ',', ';' or "
                           "'${' (its lists split there): move it to another folder")
    return text


def _verdict(label: str, log: str, seconds: float) -> Verdict:
    """The verdict read off JPF's report (module docstring)."""
    states = next((line.split(":", 1)[1].strip() for line in log.splitlines()
                   if line.startswith("states:")), "?")
    m = re.search(r"^search:.*constraints=(\d+)", log, re.M)
    constraints = int(m.group(1)) if m else 0
    results = log.split(" results", 1)[1].split(" statistics", 1)[0] if " results" in log else ""
    antlr = re.search(r"^line \d+:\d+ .*$", log, re.M)
    if antlr is not None:
        return Verdict(label, "error", states, seconds,
                       f"the property does not parse: {antlr.group(0)}")
    if "no errors detected" in results:
        if constraints:
            return Verdict(label, "error", states, seconds,
                           f"a search constraint was hit {constraints} time(s): not a proof")
        return Verdict(label, "holds", states, seconds)
    err = re.search(r"^error #1: (.*)$", results, re.M)
    if err is not None and "An Accepting Path has been found" in err.group(1):
        path = len(re.findall(r"\[MS: \d+, BS: \d+, UN: \d+\]", log))
        return Verdict(label, "violated", states, seconds,
                       f"an accepting path of {path} product states")
    if err is not None:
        return Verdict(label, "error", states, seconds, err.group(1).strip())
    why = next((line.strip() for line in log.splitlines()
                if re.search(r"Exception|Error:", line)), log.strip().splitlines()[-1:] or [""])
    return Verdict(label, "error", states, seconds,
                   f"JPF gave no result: {why if isinstance(why, str) else why[0]}")


def check_agent(tools: Tools, folder: Path, labels: Sequence[str] = (),
                timeout: float = 1800) -> Iterator[Verdict]:
    """Compile the agent in ``folder`` and check ``labels`` (default: every property), in
    the ``.psl``'s order: each verdict as its JPF run ends (one run at a time: a run may take
    minutes and gigabytes).

    Raises:
        AjpfRunError: the folder's files, javac, or a label the ``.psl`` does not have (before
            any run)."""
    base = agent_in(folder)
    known = psl_labels(folder / f"{base}.psl")
    unknown = [x for x in labels if x not in known]
    if unknown:
        raise AjpfRunError(f"{folder / (base + '.psl')} has no property {', '.join(unknown)} "
                           f"(it has {', '.join(known) or 'none'})")
    if not known:
        raise AjpfRunError(f"{folder / (base + '.psl')} states no property (every requirement "
                           "is listed there as not stated, with the reason)")
    return _runs(tools, folder, base, list(labels or known), timeout)


def _runs(tools: Tools, folder: Path, base: str, labels: list[str], timeout: float
          ) -> Iterator[Verdict]:
    with tempfile.TemporaryDirectory(prefix="fretc-ajpf-classes-") as tmp:
        classes = Path(tmp)
        compile_agent(tools, folder, base, classes)
        for label in labels:
            yield check_property(tools, folder, base, label, classes, timeout)
