"""``fretc check``: requirement sets analysed before any robot runs: consistency, non-vacuity,
minimal conflicting subsets and redundancy (:mod:`.analysis`, Spot queries with a budget in
:mod:`.solver` over the propositional abstraction of :mod:`.numeric_abstraction`),
realizability (:mod:`.realizability`), witness traces (:mod:`.witness`), the findings
(:mod:`.findings`) and their place in ``fretc report`` (:mod:`.report`)."""
