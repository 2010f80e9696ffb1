"""From requirement entries (``fretish.files``) to compiled requirements: the parsed sentence,
its formalization and every printed form, or the error that stopped it. One requirement's
failure never stops the others."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from fretc.common.errors import FretishError, render_diagnostic
from fretc.fretish.ast import Requirement
from fretc.fretish.entry import RequirementEntry

from fretc.compiler.instantiate import formula_text, instantiate
from fretc.compiler.printers import mangle
from fretc.compiler.semantics import Formalization, SemanticsError

if TYPE_CHECKING:
    from fretc.compiler.pctl import Pctl
    from fretc.compiler.ir import ProbabilityBound

PT_FTP = "(Z FALSE)"

#: the keys of :meth:`Compiled.to_json` for a requirement that formalized, in order
FORMALIZED_KEYS = ("id", "text", "source", "line", "parent", "rationale", "key", "ft",
                   "ft_inf", "pt", "ft_spot", "ft_inf_spot", "variables", "variables_fret",
                   "ticks", "warnings", "pt_causal")


@dataclass
class Compiled:
    """One requirement after compilation.

    ``entry`` is the :class:`fretc.fretish.files.RequirementEntry`; ``formalization`` is set when
    it formalized, ``error`` (a :class:`FretishError`) otherwise; free-form requirements
    have neither.
    """

    entry: RequirementEntry
    formalization: Formalization | None = None
    error: FretishError | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    # read-only delegations, same shape as compiler.codegen.MonitorSource's (kept: one property per
    # field)
    @property
    def id(self) -> str:
        """The requirement's id (its entry's)."""
        return self.entry.id

    @property
    def text(self) -> str:
        """The requirement's FRETish text (its entry's)."""
        return self.entry.text

    @property
    def requirement(self) -> Requirement | None:
        """The parsed requirement (:class:`fretc.fretish.ast.Requirement`), or None if it did not parse."""
        return self.entry.requirement

    @property
    def freeform(self) -> bool:
        """True for a free-form requirement (no FRET formalization)."""
        r = self.entry.requirement
        return bool(r is not None and r.freeform)

    @property
    def source_hash(self) -> str:
        """SHA-256 of the requirement's identity and text (id, text, tick period), hex."""
        period = self.entry.tick_period
        blob = f"{self.id}\n{self.text}\n{period if period is not None else ''}"
        import hashlib  # lazy: loading OpenSSL is start-up time --emit ltl does not need
        return hashlib.sha256(blob.encode("utf-8")).hexdigest()

    @property
    def smv_text(self) -> dict[str, str]:
        """FRET/SMV text of the formulas: ``{"ft": ..., "ft_inf": ..., "pt": ...}`` (pt with
        FTP printed ``(Z FALSE)``, as FRET does), printed once (from the template key's
        printed form where it applies, :func:`fretc.compiler.instantiate.formula_text`)."""
        if "smv" not in self._cache:
            f = self.formalization
            assert f is not None  # (the printed forms are asked of a formalized requirement)
            self._cache["smv"] = {w: formula_text(f, w)
                                  for w in ("ft", "ft_inf", "pt")}
        return self._cache["smv"]

    def spot(self, which: str) -> str:
        """Spot text of ``ft`` or ``ft_inf``."""
        key = ("spot", which)
        if key not in self._cache:
            f = self.formalization
            assert f is not None  # (the printed forms are asked of a formalized requirement)
            self._cache[key] = formula_text(f, which + "_spot")
        return self._cache[key]

    @property
    def probability(self) -> ProbabilityBound | None:
        """The requirement's probability bound (:class:`fretc.compiler.ir.ProbabilityBound`), or
        None: a requirement without ``with probability``, or one that did not formalize."""
        f = self.formalization
        return None if f is None else getattr(f, "probability", None)

    def pctl_form(self) -> Pctl | None:
        """The requirement's probabilistic form (:class:`fretc.compiler.pctl.Pctl`: FRET's
        five-part key, the bounds where FRET 3.1 puts them, per trigger, around ft_inf),
        computed once; None for a requirement that did not formalize or is free-form."""
        if self.formalization is None or self.requirement is None:
            return None
        if "pctl" not in self._cache:
            from fretc.compiler.pctl import pctl_of  # lazy: only probability requirements
            self._cache["pctl"] = pctl_of(self.requirement, self.entry.tick_period)
        return self._cache["pctl"]

    def pctl(self) -> str | None:
        """The PCTL of a probability requirement in PRISM's syntax, its bounds where FRET
        puts them (per trigger, :mod:`fretc.compiler.pctl`), e.g. ``P>=1 [ ((G (((!
        too_close) & (X too_close)) => (X P>=0.9 [ (F<=1 stopped) ]))) & (too_close =>
        P>=0.9 [ (F<=1 stopped) ])) ]``; None without a bound, or when PRISM's properties
        cannot say it (:meth:`pctl_unsupported` says why)."""
        return self._pctl_text()[0]

    def pctl_unsupported(self) -> str | None:
        """Why a probability requirement has no PCTL form (:meth:`pctl` None): its path
        formula holds what PRISM's properties cannot say (a past-time operator or function,
        a function PRISM does not have: :class:`fretc.compiler.pctl.PrismUnsupported`'s
        message); None when it has one, or has no bound."""
        return self._pctl_text()[1]

    def _pctl_text(self) -> tuple[str | None, str | None]:
        """``(pctl, why none)``, computed once."""
        if "pctl_text" not in self._cache:
            form = self.pctl_form() if self.probability is not None else None
            got: tuple[str | None, str | None] = (None, None)
            if form is not None:
                from fretc.compiler.pctl import PrismUnsupported

                try:
                    got = (form.text, None)
                except PrismUnsupported as exc:
                    got = (None, str(exc))
            self._cache["pctl_text"] = got
        return self._cache["pctl_text"]

    @property
    def key_pctl(self) -> str | None:
        """FRET's five-part key ``scope,condition,probability,timing,response``
        (:func:`fretc.compiler.pctl.pctl_key`); None when not formalized."""
        f = self.formalization
        if f is None:
            return None
        from fretc.compiler.pctl import pctl_key
        return pctl_key(f.key, self.probability is not None)

    def location(self) -> str:
        """``file:line`` of the requirement."""
        return f"{self.entry.source}:{self.entry.line}"

    def printed(self) -> tuple:
        """The five printed forms ``(ft, ft_inf, pt, ft_spot, ft_inf_spot)`` (FRET/SMV, pt
        with FTP as ``(Z FALSE)``; Spot), computed in that order, each as :meth:`smv` and
        :meth:`spot` give it; ``ValueError`` where Spot has no form. A template
        instantiation (:class:`fretc.compiler.instantiate.InstantiatedFormalization`) fills its
        atoms' texts in once for all five."""
        f = self.formalization
        forms = getattr(f, "printed", None)
        if forms is not None:
            return forms()
        return (self.smv_text["ft"], self.smv_text["ft_inf"], self.smv_text["pt"], self.spot("ft"),
                self.spot("ft_inf"))

    def json_forms(self, enc: Callable[[str], str], seps: tuple) -> str | None:
        """The five printed forms as JSON strings escaped by ``enc`` and separated by
        ``seps``, in one piece, where the formalization gives them so
        (:meth:`fretc.compiler.instantiate.InstantiatedFormalization.json_forms`); else None."""
        forms = getattr(self.formalization, "json_forms", None)
        return None if forms is None else forms(enc, seps)

    def json_values(self, texts: bool = True) -> tuple | None:
        """The values of :meth:`to_json`, in the order of :data:`FORMALIZED_KEYS`, for a
        requirement that formalized (no error); None for any other (free-form, failed).
        ``texts=False``: None in place of the five printed forms (nothing printed)."""
        f = self.formalization
        if f is None or self.error is not None or self.probability is not None:
            return None  # (a probability requirement has two more keys: to_json's own)
        e = self.entry
        ft, ft_inf, pt, ft_spot, ft_inf_spot = self.printed() if texts else (None,) * 5
        variables = f.variables
        return (e.id, e.text, e.source, e.line, e.parent, e.rationale, f.key, ft, ft_inf, pt,
                ft_spot, ft_inf_spot, variables, [mangle(v) for v in variables], f.ticks,
                f.warnings, f.pt_causal)

    def to_json(self) -> dict:
        """The ``--json`` object: ``id``, ``text``, ``source``, ``key``, ``ft``, ``ft_inf``,
        ``pt`` (FRET syntax), ``ft_spot``, ``ft_inf_spot``, ``variables`` (the names as
        written, quotes removed, as FRET's list), ``variables_fret`` (the same names as
        FRET's formulas print them: ``"weird var"`` -> ``_DQT_weird_SPC_var_DQT_``),
        ``warnings``, for a probability requirement FRET's five-part ``key`` with the four-part
        one as ``key_ltl``, ``probability`` (``{"op", "p", "text"}``), ``pctl``
        (:meth:`pctl`; null where PRISM cannot say it, with ``pctl_unsupported`` the reason)
        and ``pctl_bounds`` (where its bounds sit,
        :func:`fretc.compiler.pctl.bound_structure`), and ``error`` (``message``, ``line``, ``column``) when it failed. A formalized
        requirement's keys are :data:`FORMALIZED_KEYS`, its values :meth:`json_values`."""
        values = self.json_values()
        if values is not None:
            return dict(zip(FORMALIZED_KEYS, values))
        e = self.entry
        out = {"id": e.id, "text": e.text, "source": e.source, "line": e.line,
               "parent": e.parent, "rationale": e.rationale}
        if self.formalization is not None:
            f = self.formalization
            out.update({
                "key": f.key, "ft": self.smv_text["ft"], "ft_inf": self.smv_text["ft_inf"],
                "pt": self.smv_text["pt"], "ft_spot": self.spot("ft"),
                "ft_inf_spot": self.spot("ft_inf"), "variables": f.variables,
                "variables_fret": [mangle(v) for v in f.variables],
                "ticks": f.ticks, "warnings": f.warnings, "pt_causal": f.pt_causal,
            })
            b = self.probability
            if b is not None:  # FRET's keys: key (five-part), key_ltl (four-part)
                form = self.pctl_form()
                assert form is not None  # (it formalized)
                out["key"], out["key_ltl"] = form.key, f.key
                out["probability"] = dict(b.to_json(), text=b.text)
                out["pctl"] = self.pctl()  # None, and why, where PRISM cannot say it
                if out["pctl"] is None:
                    out["pctl_unsupported"] = self.pctl_unsupported()
                out["pctl_bounds"] = form.bounds
        elif self.freeform:
            out.update({"key": None, "freeform": True})
        if self.error is not None:
            err = self.error
            out["error"] = {"message": getattr(err, "message", str(err)),
                            "line": getattr(err, "line", e.line),
                            "column": getattr(err, "column", e.column),
                            "text": str(err)}
        return out


def compile_entry(entry: RequirementEntry) -> Compiled:
    """Formalize one :class:`fretc.fretish.files.RequirementEntry` (never raises for bad input)."""
    if entry.error is not None:
        return Compiled(entry, error=entry.error)
    req = entry.requirement
    if req is None or req.freeform:
        return Compiled(entry)
    try:
        # the printed formulas by template instantiation; the IR on first use
        return Compiled(entry, formalization=instantiate(req, entry.tick_period))
    except SemanticsError as exc:
        return Compiled(entry, error=_locate(exc, entry))


def compile_entries(entries: Iterable) -> list[Compiled]:
    """:func:`compile_entry` of each entry, in order."""
    return [compile_entry(e) for e in entries]


def _locate(exc: SemanticsError, entry: RequirementEntry) -> FretishError:
    """Give a semantics error the file position of the span it names."""
    span = exc.span
    line = span.line if span is not None and span.line else entry.line
    column = span.column if span is not None and span.line else entry.column
    exc.source, exc.line, exc.column = entry.source, line, column
    exc.args = (render_diagnostic(entry.source, line, column, exc.message),)
    return exc
