"""A calibration (and a noise report) in the files its consumers load: Kalibr, OpenVINS,
VINS-Mono/VINS-Fusion, ORB-SLAM3, KF-GINS, PX4, ArduPilot, IMU-TK and imucal.

One module per consumer, one entry in :data:`~accelcal.export.registry.CONSUMERS`, one
conformance suite.  Each module's docstring gives the consumer's own equations (repository,
file, line) and how accelcal's model maps onto them; a test per consumer corrects raw
data as that source does and checks the result against ``accelcal apply``.

:func:`accelcal.export.api.export` checks what the consumer needs (a gyroscope, a noise
report), that the calibration is plausible, writes, and refuses a lossy export only when
asked for exactness.  Importing this package imports the registry only, no numerical
library (``accelcal --help`` lists the consumers).
"""

from __future__ import annotations

from .registry import CONSUMERS, add_section, consumer_named, consumers_help

__all__ = ["CONSUMERS", "add_section", "consumer_named", "consumers_help"]
