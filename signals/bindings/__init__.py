"""Signal bindings: how each FRET variable is computed from recorded messages.

A binding file (TOML, read with :mod:`tomllib`) gives the clock (``[tick]``: a period with
sample-and-hold, or one tick per message of a topic) and, per variable, an expression over
message fields (``too_close = "min(/scan.ranges) < 0.9"``), kept apart from the requirement
text so that one requirement set audits the simulator and the robot (../shared/DESIGN.md,
"Signals are declared, never guessed"). The language (grammar ``grammar.lark``), its values,
units, NaN and LaserScan rules (REP 117) are docs/bindings.md; the modules, in the order they
build on each other, are in ARCHITECTURE.md ("The binding language").

May import: ``fretc.common``, ``fretc.fretish`` and ``fretc.logs`` (the schemas of a log's
types, the names of its encodings' constants) for the type checks; it sits below the rest
of ``fretc.signals`` (the sampling), which uses it.

Design notes: ARCHITECTURE.md, `signals/bindings/__init__.py`."""

from __future__ import annotations

from fretc.signals.bindings.binding import Binding, compile_expression, operand_signals, parse_inline
from fretc.signals.bindings.compile import EvalState
from fretc.signals.bindings.expression import Field, unparse
from fretc.signals.bindings.extract import LASER_SCAN, Valid, make_extractor
from fretc.common.units import parse_duration

from fretc.signals.bindings.files import load_bindings, parse_bindings
from fretc.signals.bindings.spec import DEFAULT_HEADER_LAG_NS, Bindings, LogSelector, TickSpec, make_bindings
from fretc.signals.bindings.typecheck import check_types

__all__ = [
    "Binding",
    "Bindings",
    "TickSpec",
    "EvalState",
    "Valid",
    "load_bindings",
    "parse_bindings",
    "parse_inline",
    "make_bindings",
    "parse_duration",
    "compile_expression",
    "LASER_SCAN",
    "check_types",
    "LogSelector",
    "operand_signals",
    "make_extractor",
    "Field",
    "unparse",
    "DEFAULT_HEADER_LAG_NS",
]
