"""``fretc shield``: the Safety System synthesized from the requirements.

The winning region of ``fretc check``'s safety game (:mod:`fretc.check.safety_game`) as a
shield (Bloem, Könighofer, Könighofer, Wang, "Shield Synthesis", TACAS 2015): every tick it
reads the inputs and the controller's proposed outputs and returns outputs that keep every
enforced requirement winnable, the proposal unchanged whenever it does.
"""
