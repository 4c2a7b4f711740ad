"""Reproduction of Batista, Silvestre, Oliveira, Cardeira (2011) on the methods of
:mod:`accelcal.batista`: stepped table attitudes (:mod:`.trajectory`), Monte Carlo
experiments as tidy tables (:mod:`.montecarlo`), config → experiments
(:mod:`.experiment`), ledger rows (:mod:`.claims`) and figures (:mod:`.figures`).
"""
