"""``python -m accelcal.cli``."""

import sys

from . import main

sys.exit(main())
