"""The JUnit XML file of ``fretc audit --junit FILE``: a ``testsuite`` per log, a ``testcase``
per requirement, for CI. Deterministic (no wall-clock times: every ``time`` is 0); every
text and attribute made legal XML 1.0.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

from fretc.common.textsafe import xml_text
from fretc.common.units import format_offset

from fretc.reports.terminal import short_log_name
from fretc.audit.verdict import LogAudit

__all__ = ["junit_xml"]


def junit_xml(logs: list[LogAudit], statistics: list | None = None) -> str:
    """JUnit XML: a ``testsuite`` per log, a ``testcase`` per requirement (``failure`` when
    violated, ``error`` when not audited; vacuous passes say so in ``system-out``).

    With ``statistics`` (:class:`fretc.audit.statistics.RequirementStatistics` list) a requirement
    with a probability bound follows its statistical verdict: its per-log cases pass
    (a violated run says so in ``system-out``: one run does not decide a probability), and a
    ``statistics`` suite has one case per such requirement: a ``failure`` when it fails, an
    ``error`` (type ``undecided``) when undecided."""
    root = ET.Element("testsuites", name="fretc audit")
    tot = {"tests": 0, "failures": 0, "errors": 0}
    bounded = {s.id for s in statistics or () if s.bound is not None}
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
            out = [v.text]
            if v.verdict == "violated" and v.requirement in bounded:
                out.append("verdict: violated on this run; a probability requirement is "
                           "judged over the runs (suite 'statistics')")
            elif v.verdict == "violated":
                counts["failures"] += 1
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
    if bounded:
        _statistics_suite(root, [s for s in statistics if s.bound is not None], tot)
    for k, n in tot.items():
        root.set(k, str(n))
    _xml_safe(root)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _statistics_suite(root, stats: list, tot: dict) -> None:
    """The ``statistics`` testsuite: one case per probability requirement, its statistical
    verdict (``holds`` passes)."""
    suite = ET.SubElement(root, "testsuite", name="statistics")
    counts = {"tests": 0, "failures": 0, "errors": 0}
    for st in stats:
        counts["tests"] += 1
        case = ET.SubElement(suite, "testcase", classname="fretc.audit.statistics",
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


