"""Write the expected verdicts of a ledger (the CI reproduction check compares with them).

    .venv/bin/snakemake all --configfile config/ci.yaml
    .venv/bin/python tools/expected_verdicts.py results/claims.csv > tests/expected_verdicts.ci.csv

Run it only after reading why a verdict changed: the file is the project's statement of
which claims reproduce at the CI scale, and a change to it belongs in the commit message.
"""

import sys

import pandas as pd

from accelcal_repro.claims import expected_verdicts, read_claims

if len(sys.argv) != 2:
    sys.exit("usage: expected_verdicts.py results/claims.csv")
sys.stdout.write(expected_verdicts(read_claims(sys.argv[1])).to_csv(index=False, lineterminator="\n"))
