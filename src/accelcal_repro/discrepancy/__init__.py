"""The discrepancy benchmark: simulated recordings with hidden effects through
:func:`accelcal.discrepancy.discrepancy`, scored (:mod:`.benchmark`), and its figures
(:mod:`.figures`)."""
