"""Hostile FRET exports for the tests of ``--emit cocospec`` and ``--emit ogma``: FRET JSON
projects (``{"requirements": [...], "variables": [...]}``) whose Internal variables'
``assignment`` texts, variable names and requirement ids are chosen to break a Lustre file
that embeds them: ``;`` and ``tel`` ending the contract early, a foreign ``node`` and a second
``contract``, comment openers (``--``, ``(*``, ``/*``, ``//``) and closers, Kind 2's
annotations (``--%``, ``(*@``), ``and then``, quotes, backslashes and line breaks; names that
are Lustre keywords (``node``, ``let``, ``tel``, ``var`` ...), fretc's library nodes (``H``,
``delay2``, ``absReal``) or its renamings of them (``node_v``, ``node_v_2``), and names that
start with ``then``/``else``.

:data:`INJECTION` is the attack of the hostile round's report as written."""

from __future__ import annotations

import json

from hypothesis import strategies as st

from fretc.fretish.words import FRET_RESERVED, RESERVED_WORDS

#: an assignment that, written as it is, closes the contract and adds a node and a contract
INJECTION = ('a; tel\nnode evil(x: bool) returns (y: bool); let y = x; tel\n'
             'contract Other(a: bool) returns (); let guarantee "g" a')

#: variable names: keywords of Kind 2 and of FRET's Lustre subset, library nodes, renamings
NAMES = ("node", "let", "tel", "var", "contract", "returns", "const", "type", "int", "real",
         "bool", "assume", "guarantee", "mode", "lsh", "fby", "merge", "current", "when",
         "function", "include", "H", "O", "S", "YtoPre", "OT", "delay", "delay2", "absReal",
         "preBool", "node_v", "node_v_2", "let_v", "var_v", "thenx", "elsewhere", "a", "b",
         "x", "k", "lustreC")
#: those a FRETish requirement can read
FRETISH_NAMES = tuple(n for n in NAMES
                      if n.lower() not in RESERVED_WORDS and n not in FRET_RESERVED)

#: fragments of assignments that break a file they are pasted in
FRAGMENTS = (";", "; tel", "\n" + INJECTION, " -- ;", " --", " (* ", " *) ", '"', "\\",
             "\n", " /* ", " // ", " --%PROPERTY x;", " (*@contract import X() returns (); *)",
             " and then ", " or else ", "'", "node evil() returns (); let tel",
             "1.", ".5", "2e3", "-7", "9" * 120, "$", "\u202e", "\x00")


def _expressions(names: st.SearchStrategy) -> st.SearchStrategy:
    """Lustre expressions of FRET's subset over ``names`` (types not minded)."""
    leaf = st.one_of(names, st.sampled_from(["true", "false", "1.", ".5", "2e3", "3",
                                             "0.0"]))

    def grow(sub: st.SearchStrategy) -> st.SearchStrategy:
        return st.one_of(
            st.tuples(sub, st.sampled_from(["and", "or", "xor", "=>", "=", "<>", "<", "+",
                                            "-", "*", "/", "->", "mod"]), sub)
            .map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
            st.tuples(st.sampled_from(["not ", "pre ", "- ", "pre("]), sub)
            .map(lambda t: f"{t[0]}{t[1]}" + (")" if t[0].endswith("(") else "")),
            st.tuples(sub, sub, sub).map(lambda t: f"if {t[0]} then {t[1]} else {t[2]}"))

    return st.recursive(leaf, grow, max_leaves=6)


def assignments() -> st.SearchStrategy:
    """Assignment texts: expressions of the subset over :data:`NAMES`, the same with a
    hostile fragment before, inside or after, and free text of the fragments."""
    good = _expressions(st.sampled_from(NAMES))
    fragment = st.sampled_from(FRAGMENTS)
    return st.one_of(
        good,
        st.tuples(good, fragment).map("".join),
        st.tuples(fragment, good).map("".join),
        st.tuples(good, fragment, good).map(" ".join),
        st.lists(st.one_of(fragment, st.sampled_from(NAMES)), min_size=1, max_size=6)
        .map(" ".join),
        st.just(INJECTION))


def ids() -> st.SearchStrategy:
    """Requirement ids: plain, or holding quotes, backslashes, line breaks, comment
    openers and closers."""
    return st.one_of(
        st.sampled_from(["R1", "assumption_A", "a b"]),
        st.text(st.sampled_from('R1"\\\n\r\t*()-/;@%!x \u2028'), min_size=1, max_size=12)).filter(str.strip)


@st.composite
def exports(draw: st.DrawFn) -> str:
    """The JSON text of a FRET project with one component ``c``: Input and Output
    variables, Internal variables with hostile assignments, 1-3 requirements reading them."""
    names = draw(st.lists(st.sampled_from(NAMES), min_size=3, max_size=9, unique=True))
    n_in = draw(st.integers(1, len(names) - 2))
    inputs, outputs, internal = names[:n_in], names[n_in:n_in + 1], names[n_in + 1:]
    variables = [{"variable_name": n, "component_name": "c", "idType": "Input",
                  "dataType": "boolean"} for n in inputs]
    variables += [{"variable_name": n, "component_name": "c", "idType": "Output",
                   "dataType": "boolean"} for n in outputs]
    for n in internal:
        variables.append({"variable_name": n, "component_name": "c", "idType": "Internal",
                          "dataType": draw(st.sampled_from(["boolean", "double", ""])),
                          "assignment": draw(assignments())})
    readable = [n for n in names if n in FRETISH_NAMES] or ["a"]
    reqs = []
    for rid in draw(st.lists(ids(), min_size=1, max_size=3, unique=True)):
        used = draw(st.lists(st.sampled_from(readable), min_size=1, max_size=3))
        op = draw(st.sampled_from([" & ", " | ", " => "]))
        reqs.append({"reqid": rid, "fulltext": "the c shall always satisfy "
                     + op.join(used)})
    return json.dumps({"requirements": reqs, "variables": variables})
