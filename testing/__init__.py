"""Requirements-based testing: tests generated from the requirements and run against a system.

* :mod:`.generate` (``fretc testgen``): a trace per coverage obligation of each requirement,
  found by ``fretc check``'s engines and confirmed by the audit's judge, with its expected
  verdict;
* :mod:`.invert` and :mod:`.mcap_log` (``--bindings``): a test as an MCAP log of the bound
  topics, the bindings inverted and the log read back through the audit's own sampler;
* :mod:`.pytest_file` (``--pytest``): the generated pytest file;
* :mod:`.testrun` (``fretc testrun``): a test against a system's log, by the pass rule;
* :mod:`.drive_plan`: how a test trace drives the simulated Safe-ROS robot
  (``python -m fretc.sim drive``).

Only the last step of each is an audit: the package sits after :mod:`fretc.audit` in the
pipeline's order (ARCHITECTURE.md).
"""
