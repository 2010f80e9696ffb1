"""Signal bindings: how each FRET variable is computed from recorded messages.

Bindings live apart from the requirement text (../shared/DESIGN.md, "Signals are declared,
never guessed"): one requirement set audits both the simulator and the real robot by swapping the
binding file.  A binding file is TOML (read with :mod:`tomllib`)::

    [tick]
    period = "100 ms"      # fixed period with sample-and-hold, or
    # topic = "/scan"      # one tick per message of this topic (exactly one of the two)
    # nominal_rate = "10 Hz" # topic only: converts durations in time units to ticks
    time = "log"           # time base: "log" (MCAP log time, default) or "header"
    # header_lag = "500 ms" # time="header" only: how late a message may arrive (default 1 s)

    [variables]
    too_close = "min(/scan.ranges) < 0.9"
    stopped = "abs(/cmd_vel.linear.x) < 1e-3 & abs(/cmd_vel.angular.z) < 1e-3"
    scan_stale = "age(/scan) > 0.3"

Durations are a number with a unit (:mod:`fretc.common.units`, the grammar of the requirement
files' ``tick_period`` too): ``ns``, ``us``, ``ms``, ``s``, ``min``, ``h`` (or their long
names, ``milliseconds``), or a frequency in ``Hz`` (period = 1/f); a bare TOML number is
seconds.

Expression language (grammar: ``signals/bindings/grammar.lark``), loosest binding first:

=================  ==========================================================================
``a -> b``         implication (right-assoc.);  ``a <-> b`` equivalence
``a | b``          or;  ``a & b`` and;  ``! a`` not (looser than comparisons: ``!x < 3`` is
                   ``!(x < 3)``)
``< <= > >= = !=`` comparisons (``==`` also accepted); they do not chain
``+ - * /``        arithmetic; unary ``-``.  ``x / 0`` is ±inf (nan for 0/0), as IEEE 754
``/topic.a.b[i]``  a message field (Foxglove's message path syntax): topic name (any topic
                   quoted: ``"ORB-SLAM".pose``), then fields by ``.``, array items by
                   ``[i]`` (negative counts from the end), slices ``[lo:hi]`` and filters
                   ``{name=="battery"}``, after which the path applies to each item
``1.5 2e-3 true``  numbers and booleans; ``"text"`` strings (``=``, ``!=``, ``in [...]``);
                   ``NAME`` in capitals: a named constant of a message definition
``f(...)``         ``abs(x)``; ``norm(a, b, ...)`` = sqrt(a²+b²+...) or ``norm(array)``;
                   ``min``/``max`` of an array or of several values; ``mean``, ``any``,
                   ``all``, ``count`` (number of true/non-zero items), ``len`` of an array;
                   ``age(/topic)`` = seconds from the topic's latest message to the tick;
                   ``joint(/js.position, "name")`` a joint by name; ``tf("a", "b").x``
                   (``.y .z .yaw .age``) a transform from /tf and /tf_static
=================  ==========================================================================

Values: booleans, float64 numbers (integer fields are read as floats), and arrays (numeric
arrays are read as float64).  Arithmetic and comparisons apply item by item to arrays
(numpy), so ``count(/scan.ranges < 0.9)`` counts close returns.  A variable must end as a
boolean or a number.  NaN compares false and counts as true in ``& | ! ->`` (numpy).
Reductions of an empty array: ``min`` → +inf, ``max`` → -inf, ``mean`` → nan, ``any`` →
false, ``all`` → true, ``count``/``len``/``norm`` → 0.  Outside LaserScans NaN propagates
through ``min``/``max``/``mean``.

LaserScan ranges (REP 117): a field path ending in ``ranges`` of a ``sensor_msgs/LaserScan``
(without an index) yields only the valid returns: values inside
``[range_min, range_max]``; NaN, +inf and out-of-range values are ignored by every
item-wise operation and reduction (``len`` counts valid returns).  So ``min(/scan.ranges)``
is +inf when no return is valid.  REP 117's -inf ("detected, too close to measure") is read
as ``range_min``, so a too-close object is never hidden from ``min``.
``/scan.ranges[i]`` is the raw value of beam i.

Each binding is parsed once (Lark, LALR) and compiled to nested Python closures (no eval of
user text): :meth:`Binding.evaluate` for one tick, :meth:`Binding.evaluate_columns` for all
ticks at once with numpy.  Errors name the binding file, line and column and the variable.

The modules, in the order they build on each other:

* :mod:`~fretc.signals.bindings.expression`: the expression tree and its static checks;
* :mod:`~fretc.signals.bindings.parse`: the parser (Lark, ``grammar.lark``) that builds the tree;
* :mod:`~fretc.signals.bindings.paths`: topic names and strings as written in bindings;
* :mod:`~fretc.signals.bindings.extract`: a message field as a value (:func:`make_extractor`);
* :mod:`~fretc.signals.bindings.frames`: transforms between TF frames, joints by name;
* :mod:`~fretc.signals.bindings.operations`: the operations on values (per tick and vectorized);
* :mod:`~fretc.signals.bindings.compile`: an expression tree to closures;
* :mod:`~fretc.signals.bindings.binding`: :class:`Binding`, one variable, compiled;
* :mod:`~fretc.signals.bindings.typecheck`: a binding against a log's message types;
* :mod:`~fretc.signals.bindings.spec`: :class:`Bindings`, :class:`TickSpec`, :class:`LogSelector`;
* :mod:`~fretc.signals.bindings.files`: binding files (TOML).

May import: ``fretc.common``, ``fretc.fretish`` and ``fretc.logs`` (the schemas of a log's
types, the names of its encodings' constants) for the type checks; it sits below the rest
of ``fretc.signals`` (the sampling), which uses it.
"""

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
