"""accelcal_repro: the reproductions built on the accelcal library.

The papers (:mod:`.burkhard2024`, :mod:`.batista2011`, :mod:`.tereshkov`), the public
recordings (:mod:`.measured`), the discrepancy benchmark (:mod:`.discrepancy`), the
Monte Carlo engine and timing benchmark of Burkhard et al. (:mod:`.montecarlo`,
:mod:`.timing`), the claims ledger (:mod:`.claims`) and the HTML report
(:mod:`.report`).  The Snakemake workflow in ``workflow/`` wires data to them.

This package imports :mod:`accelcal`; :mod:`accelcal` never imports it.
"""
