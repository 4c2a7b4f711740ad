"""The noise stage: the noise analysis of a static recording (:mod:`accelcal.noise.report`) on
the 2.78 h ADIS16405 record against its datasheet (:mod:`.adis`), the coverage of its
term intervals on simulated records with known terms (:mod:`.coverage`), and the claims
judged from both (:mod:`.claims`)."""
