"""Verdicts rolled up to parent requirements: a requirement refined by others (its children:
the requirements whose parent links name it) is judged through them too.

The parent links are the audit document's: ``requirements[].origin.parents`` (ReqIF
SPEC-RELATIONs, Doorstop ``links``, FRET's ``parent_reqid``: :class:`fretc.fretish.entry.
Origin`), else ``requirements[].parent`` (a ``.fret`` ``parent:`` line); the items without
FRETish text (``not_formalized``) take part by their ``origin.parents``. A parent named by a
link but absent from the document is a node too (``not in the audit``).

Design notes: ARCHITECTURE.md, `reports/rollup.py`."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Rollup", "rollups", "children_of", "parents_of", "ROLLUP_ORDER", "NOT_IN_AUDIT",
           "path_text"]

#: Rolled-up verdicts, worst first.
ROLLUP_ORDER = ("violated", "unverified", "satisfied", "vacuous")
NOT_IN_AUDIT = "not in the audit"
_OWN = {"violated": "violated", "error": "unverified", "unknown": "unverified",
        "satisfied": "satisfied", "vacuous": "vacuous"}


@dataclass(frozen=True)
class Rollup:
    """One requirement's roll-up (module docstring).

    Attributes:
        id: the requirement's id.
        own: its own verdict over the runs (``satisfied``, ``vacuous``, ``violated``,
            ``unknown``, ``error``), ``not formalized`` or ``not in the audit``.
        verdict: the rolled-up verdict, one of :data:`ROLLUP_ORDER`.
        path: ids from this requirement down to the one that decides a ``violated`` or
            ``unverified`` roll-up (``(id,)`` when its own verdict decides; empty for
            ``satisfied`` and ``vacuous``).
        decided_by: that requirement's own verdict (empty for ``satisfied``, ``vacuous``).
        children: the ids of the requirements whose parent links name this one, in the
            document's order.
    """

    id: str
    own: str
    verdict: str
    path: tuple[str, ...]
    decided_by: str
    children: tuple[str, ...]

    def text(self) -> str:
        """One line: ``violated via SR-0 > R1 > R2 (R2 violated)``, or the verdict alone."""
        if not self.path:
            return self.verdict
        if len(self.path) == 1:
            return f"{self.verdict} ({self.id} itself {self.decided_by})"
        return f"{self.verdict} via {path_text(self.path)} ({self.path[-1]} {self.decided_by})"


def path_text(path: tuple[str, ...]) -> str:
    """A path of ids as written in every output: ``SR-0 > R1 > R2``."""
    return " > ".join(path)


def parents_of(doc: dict) -> dict[str, tuple[str, ...]]:
    """Requirement id -> the ids its parent links name (module docstring), for every
    requirement and not-formalized item of the audit document ``doc``, in its order."""
    out: dict[str, tuple[str, ...]] = {}
    for r in list(doc.get("requirements") or []) + list(doc.get("not_formalized") or []):
        origin = r.get("origin") if isinstance(r.get("origin"), dict) else {}
        links = [p for p in origin.get("parents") or () if isinstance(p, str) and p]
        if not links and isinstance(r.get("parent"), str) and r.get("parent"):
            links = [r["parent"]]
        out.setdefault(r["id"], tuple(dict.fromkeys(p for p in links if p != r["id"])))
    return out


def children_of(parents: dict[str, tuple[str, ...]]) -> dict[str, tuple[str, ...]]:
    """Parent id -> its children's ids (in the order of ``parents``), from
    :func:`parents_of`."""
    out: dict[str, list[str]] = {}
    for rid, ps in parents.items():
        for p in ps:
            out.setdefault(p, []).append(rid)
    return {p: tuple(c) for p, c in out.items()}


def rollups(doc: dict, own: dict[str, str]) -> dict[str, Rollup]:
    """Requirement id -> :class:`Rollup` for every requirement of ``doc`` that has children
    (the parents), including parents not in the document, in the document's order (the
    absent parents last). ``own``: id -> own verdict over the runs (``not formalized`` for
    the items without FRETish text; an id missing from it is ``not in the audit``)."""
    parents = parents_of(doc)
    children = children_of(parents)
    order = list(parents) + [p for p in children if p not in parents]
    memo: dict[str, tuple[str, tuple[str, ...], str]] = {}

    def roll(rid: str, above: frozenset) -> tuple[str, tuple[str, ...], str]:
        if rid in memo:
            return memo[rid]
        mine = own.get(rid, NOT_IN_AUDIT)
        kids = [c for c in children.get(rid, ()) if c not in above]
        found: list[tuple[str, tuple[str, ...], str]] = []
        if mine in _OWN:
            found.append((_OWN[mine], (rid,) if _OWN[mine] in ("violated", "unverified")
                          else (), mine if _OWN[mine] in ("violated", "unverified") else ""))
        elif not kids:  # not formalized (or absent) and nothing below verifies it
            found.append(("unverified", (rid,), mine))
        for c in kids:
            v, path, by = roll(c, above | {rid})
            found.append((v, (rid,) + path if path else (), by))
        best = min(found, key=lambda f: ROLLUP_ORDER.index(f[0]))
        if acyclic:  # (in a cycle the answer depends on where the walk entered it)
            memo[rid] = best
        return best

    acyclic = not any(rid in _reach(rid, children) for rid in children)

    out = {}
    for rid in order:
        if rid in children:
            v, path, by = roll(rid, frozenset())
            out[rid] = Rollup(rid, own.get(rid, NOT_IN_AUDIT), v, path, by, children[rid])
    return out


def _reach(rid: str, children: dict[str, tuple[str, ...]]) -> frozenset:
    """The ids below ``rid`` (its descendants)."""
    seen: set[str] = set()
    stack = list(children.get(rid, ()))
    while stack:
        c = stack.pop()
        if c not in seen:
            seen.add(c)
            stack.extend(children.get(c, ()))
    return frozenset(seen)

