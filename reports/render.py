"""Rendering the report's data record (:func:`fretc.reports.context.report_context`) with
the Jinja2 templates ``templates/report.html.j2`` and ``templates/report.md.j2``: the
template environment (every printed value made visible and safe), the HTML page and the
Markdown document.
"""

from __future__ import annotations

import re
from typing import Any

import jinja2
import markupsafe

from fretc.common.textsafe import md_code, visible

__all__ = ["render_html", "render_markdown"]


def _finalize(value: Any) -> Any:
    """Every value printed by a template: control and bidi characters shown escaped (XML 1.0
    forbids C0 characters; a U+202E must not reorder the page), except markup built here
    (the inlined SVG, already safe)."""
    if isinstance(value, str) and not isinstance(value, markupsafe.Markup):
        return visible(value, keep="\n\t")
    return value


#: Markdown punctuation that can start a link or an image (``[``, ``]``, ``!``), emphasis, code,
#: a heading, a table cell, an HTML tag, an entity or an autolink (CommonMark 0.31 section 2.4:
#: every ASCII punctuation character may be backslash-escaped); ``:`` breaks ``scheme:``
#: autolinks, ``www.`` is escaped on its own. Parentheses need no escape once ``]`` has one.
_MD_PUNCTUATION = re.compile(r"([\\`*_\[\]#!|<>~:&])")
_WWW = re.compile(r"(www)\.", re.IGNORECASE)


def _md(text: Any) -> str:
    """Markdown table-cell / inline text that renders as the text itself: newlines folded,
    control and bidi characters made visible, and every character that could start Markdown
    or HTML (links, images, autolinks, emphasis, headings, tags) backslash-escaped."""
    s = visible("" if text is None else str(text).replace("\n", " "))
    return _WWW.sub(r"\1\\.", _MD_PUNCTUATION.sub(r"\\\1", s))


def _code(text: Any) -> str:
    """Inline Markdown code span that no backtick run in the text can close
    (:func:`fretc.common.textsafe.md_code`)."""
    return md_code("" if text is None else str(text).replace("\n", " "))


def _env(autoescape: bool) -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("fretc.templates", ""), autoescape=autoescape,
        keep_trailing_newline=True, trim_blocks=True, lstrip_blocks=True,
        undefined=jinja2.StrictUndefined, finalize=_finalize)
    env.filters["md"] = _md
    env.filters["code"] = _code
    return env


def render_html(ctx: dict) -> str:
    """The HTML page (``templates/report.html.j2``), XHTML-well-formed so it also parses as
    XML. Text from the inputs is escaped; the timelines are inlined SVG."""
    ctx = dict(ctx)
    ctx["violations"] = [dict(v, svg_markup=markupsafe.Markup(v["svg"]))
                         for v in ctx["violations"]]
    ctx["requirements"] = [dict(r, margin_markup=markupsafe.Markup(r.get("margin_svg", "")))
                           for r in ctx["requirements"]]
    return _env(True).get_template("report.html.j2").render(**ctx)


def render_markdown(ctx: dict) -> str:
    """The Markdown report (``templates/report.md.j2``; GitHub-flavoured tables, anchors as
    ``<a id>``, timelines as links to ``timelines/*.svg``)."""
    return _env(False).get_template("report.md.j2").render(**ctx)
