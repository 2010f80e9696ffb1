"""The shared base of every fretc layer: the exception tree and its positions (:mod:`.errors`,
:mod:`.problems` for recorded data), durations and time formatting (:mod:`.units`), escaping of
user text for each output format (:mod:`.textsafe`) and the on-disk cache (:mod:`.cache`).
Imports nothing of fretc's other packages."""
