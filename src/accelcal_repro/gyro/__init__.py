"""Reproductions and measurements of the gyroscope calibration (issue: the whole IMU)."""
