"""Items joined into groups when they share a key (union-find): the connected components of
the graph whose edges are shared keys."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence
from typing import TypeVar

T = TypeVar("T")


def connected_groups(items: Sequence[T], keys: Callable[[T], Iterable[Hashable]]
                     ) -> list[list[T]]:
    """``items`` grouped when they share a key of ``keys(item)``, transitively: each group in
    input order, the groups in the order of their first item."""
    parent = list(range(len(items)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner: dict[Hashable, int] = {}
    for k, item in enumerate(items):
        for key in keys(item):
            if key in owner:
                a, b = find(owner[key]), find(k)
                if a != b:
                    parent[max(a, b)] = min(a, b)
            else:
                owner[key] = k
    out: dict[int, list[T]] = {}
    for k, item in enumerate(items):
        out.setdefault(find(k), []).append(item)
    return list(out.values())
