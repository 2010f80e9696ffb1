"""The JUnit XML file of ``fretc audit --junit FILE``: a ``testsuite`` per log, a ``testcase``
per requirement, for CI. Deterministic (no wall-clock times: every ``time`` is 0); every
text and attribute made legal XML 1.0.

Design notes: ARCHITECTURE.md, `reports/junit.py`."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

from fretc.common.textsafe import xml_text
from fretc.common.units import format_offset

from fretc.reports.terminal import short_log_name
from fretc.audit.verdict import LogAudit

__all__ = ["junit_xml", "CASE_PROPERTIES"]

#: The properties of each test case, in order (module docstring).
CASE_PROPERTIES = ("verifies", "tool", "tool_id", "verdict", "vacuous", "partial", "log",
                   "first_violation_log_time_ns", "first_violation_s", "robustness")


def junit_xml(logs: list[LogAudit], statistics: list | None = None,
              requirements: list[dict] | None = None) -> str:
    """JUnit XML: a ``testsuite`` per log, a ``testcase`` per requirement (``failure`` when
    violated, ``error`` when not audited; vacuous passes say so in ``system-out``), each
    with the ``<properties>`` of the module docstring. ``requirements``: the audit JSON's
    ``requirements`` list, whose ``origin`` gives the ``tool`` and ``tool_id`` properties
    (None: no tool properties).

    With ``statistics`` (:class:`fretc.audit.fleet.statistics.RequirementStatistics` list) a requirement
    with a probability bound follows its statistical verdict: its per-log cases pass
    (a violated run says so in ``system-out``: one run does not decide a probability), and a
    ``statistics`` suite has one case per such requirement: a ``failure`` when it fails, an
    ``error`` (type ``undecided``) when undecided."""
    root = ET.Element("testsuites", name="fretc audit")
    tot = {"tests": 0, "failures": 0, "errors": 0}
    bounded = {s.id for s in statistics or () if s.bound is not None}
    origins = {r["id"]: r["origin"] for r in requirements or ()
               if isinstance(r.get("origin"), dict)}
    for la in logs:
        suite = ET.SubElement(root, "testsuite", name=short_log_name(la.log))
        props = ET.SubElement(suite, "properties")
        for k, val in (("partial", str(la.partial).lower()),
                       ("ticks_evaluated", str(la.ticks_evaluated)),
                       ("warmup_ticks", str(la.warmup_ticks))):
            ET.SubElement(props, "property", name=k, value=val)
        counts = {"tests": 0, "failures": 0, "errors": 0}
        st = la.start_time_ns
        cls = "fretc.audit." + os.path.splitext(os.path.basename(la.log.rstrip("/")))[0]
        for v in la.verdicts:
            counts["tests"] += 1
            case = ET.SubElement(suite, "testcase", classname=cls, name=v.requirement, time="0")
            _case_properties(case, la, v, origins.get(v.requirement))
            out = [v.text]
            if v.verdict == "violated" and v.requirement in bounded:
                out.append("verdict: violated on this run; a probability requirement is "
                           "judged over the runs (suite 'statistics')")
            elif v.verdict == "violated":
                counts["failures"] += 1
                _failure(case, v, st)
            elif v.verdict == "error":
                counts["errors"] += 1
                ET.SubElement(case, "error", message=v.error or "error", type="error").text = \
                    v.error or ""
            elif v.partial or v.verdict not in ("satisfied", "vacuous"):
                # not checked to the end: an error case, never a pass (exit code 3)
                counts["errors"] += 1
                where = (f" (damage from {format_offset(la.damage_time_ns, st)})"
                         if la.damage_time_ns is not None else "")
                why = (f"partial log{where}: {v.verdict} on the messages read "
                       f"({v.unknown_ticks} ticks unknown)" if v.partial
                       else f"verdict {v.verdict}")
                if v.verdict == "unknown" and v.unknown_reason:
                    why += f" (unknown: {v.unknown_reason})"

                ET.SubElement(case, "error", message=why, type="partial").text = why
                out.append(f"verdict: {v.verdict}")
            else:
                out.append(f"verdict: {v.verdict}")
                out.extend(n for n in v.notes if n.startswith("vacuous"))
            ET.SubElement(case, "system-out").text = "\n".join(out)
        for k, n in counts.items():
            suite.set(k, str(n))
            tot[k] += n
        suite.set("time", "0")
    if bounded and statistics is not None:  # (bounded: some statistics have a bound)
        _statistics_suite(root, [s for s in statistics if s.bound is not None], tot)
    for k, n in tot.items():
        root.set(k, str(n))
    _xml_safe(root)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _failure(case, v, st: int | None) -> None:
    """The ``failure`` element of a violated requirement: where it first failed."""
    fv = v.first_violation
    msg = f"{v.requirement} violated"
    body = []
    if fv is not None:
        msg += f" at {format_offset(fv.at.time_ns, st)} (tick {fv.at.tick})"
        if fv.trigger is not None:
            msg += (f"; trigger at {format_offset(fv.trigger.time_ns, st)} "
                    f"(tick {fv.trigger.tick})")
        body = [fv.obligation, fv.reason]
    if v.partial:
        msg += " [partial log]"
    ET.SubElement(case, "failure", message=msg, type="violated").text = \
        "\n".join(x for x in [v.text] + body if x)


def _number(x: float) -> str:
    """A float as the property's text: ``repr`` (exact, round-trips), ``inf``/``-inf``."""
    return "inf" if x == float("inf") else "-inf" if x == float("-inf") else repr(float(x))


def _case_properties(case, la: LogAudit, v, origin: dict | None) -> None:
    """The ``<properties>`` of one test case (module docstring)."""
    fv = v.first_violation
    at = fv.at if fv is not None else None
    values = {"verifies": v.requirement,
              "tool": origin.get("format") if origin else None,
              "tool_id": origin.get("tool_id") if origin else None,
              "verdict": v.verdict, "vacuous": str(v.verdict == "vacuous").lower(),
              "partial": "true" if v.partial else None, "log": la.log,
              "first_violation_log_time_ns": (str(at.log_time_ns) if at is not None
                                              and at.log_time_ns is not None else None),
              "first_violation_s": (repr(round((at.time_ns - la.start_time_ns) / 1e9, 9))
                                    if at is not None and la.start_time_ns is not None
                                    else None),
              "robustness": None if v.robustness is None else _number(v.robustness)}
    props = ET.SubElement(case, "properties")
    for name in CASE_PROPERTIES:
        if values[name] is not None:
            ET.SubElement(props, "property", name=name, value=str(values[name]))


def _statistics_suite(root, stats: list, tot: dict) -> None:
    """The ``statistics`` testsuite: one case per probability requirement, its statistical
    verdict (``holds`` passes)."""
    suite = ET.SubElement(root, "testsuite", name="statistics")
    counts = {"tests": 0, "failures": 0, "errors": 0}
    for st in stats:
        counts["tests"] += 1
        case = ET.SubElement(suite, "testcase", classname="fretc.audit.fleet.statistics",
                             name=st.id, time="0")
        b = st.bound
        lo, hi = st.interval
        line = (f"P(satisfied) {b['op']} {b['p']:g}: {st.successes}/{st.trials} runs, "
                f"interval [{lo:.6g}, {hi:.6g}] at {100 * st.confidence:g} % "
                f"(unknown runs: {st.unknown_policy}); verdict {st.verdict}")
        if st.verdict == "fails":
            counts["failures"] += 1
            ET.SubElement(case, "failure", message=f"{st.id} fails: {line}",
                          type="fails").text = line
        elif st.verdict == "undecided":
            counts["errors"] += 1
            ET.SubElement(case, "error", message=f"{st.id} undecided: {st.why}",
                          type="undecided").text = f"{line}\n{st.why}"
        ET.SubElement(case, "system-out").text = line
    for k, n in counts.items():
        suite.set(k, str(n))
        tot[k] += n
    suite.set("time", "0")


def _xml_safe(root) -> None:
    """Make every attribute and text of the tree legal XML 1.0 (a NUL in a requirement id
    must not make the file unparseable): :func:`fretc.common.textsafe.xml_text`."""
    for el in root.iter():
        for k, val in list(el.attrib.items()):
            el.set(k, xml_text(val, keep=""))
        if el.text:
            el.text = xml_text(el.text)


