"""The discrepancy figures of the reproductions label every effect of the table (accelcal_repro.discrepancy.figures).

Moved from tests/test_effects.py, whose other tests use the core alone: a core test file
may not import accelcal_repro (tests/test_core_tests.py)."""

import pytest
from accelcal.effects import EFFECT_IDS, EFFECTS


def test_the_figures_label_every_effect_of_the_table():
    pytest.importorskip("matplotlib")  # the figures module draws with it
    from accelcal_repro.discrepancy.figures import LABELS

    assert {e: LABELS[e] for e in EFFECT_IDS} == {e: EFFECTS[e].label for e in EFFECT_IDS}
