"""The offline engines that decide a requirement over the sampled trace of a log, each from
the columns the audit keeps (one array per FRET variable, one item per tick):

* :mod:`fretc.monitors.stepwise`: the generated monitor's ``step()`` on every tick (the
  code ``fretc FILE --emit monitor`` gives users), ``finish()`` for FRET's finite-trace
  verdict and ``status`` for the LTL3 one;
* :mod:`fretc.monitors.vectorized`: the same pt formula (compiler IR) and LTL3 automata
  computed for all ticks at once with numpy;
* :mod:`fretc.monitors.interval`: FRET's interval semantics (scope intervals, triggers,
  obligations), the evidence behind every verdict and the only engine of requirements whose
  pt formula needs a future-time function.
"""
