"""ORB-SLAM3's IMU settings: ``IMU.NoiseGyro``, ``IMU.NoiseAcc``, ``IMU.GyroWalk``,
``IMU.AccWalk``, ``IMU.Frequency``.

ORB-SLAM3's own equations (UZ-SLAMLab/ORB_SLAM3): ``src/Tracking.cc``
(``Tracking::newParameterLoader`` / ``ParseIMUParamFile``): ``sf = sqrt(freq)``,
``IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf)``; ``src/ImuTypes.cc`` (``Calib::Set``:
``Cov = diag(ng², na²)``, ``CovWalk = diag(ngw², naw²)``; ``IntegrateNewMeasurement``: the
velocity increment's noise ``B Cov Bᵀ`` with ``B = R dt``, the walk ``+= CovWalk`` per
sample).  A velocity step gets ``(N √f)² dt² = N² dt`` and a bias step ``(K / √f)² = K² dt``:
the file holds the continuous-time density ``N`` and random walk ``K``.  ORB-SLAM3 has
no IMU intrinsics: the summary says what feeding it raw data costs.
"""

from __future__ import annotations

from .base import APPLY_FIRST, Export, ExportError, intrinsics_left_out, noise_rate, noise_value

KEYS = (("IMU.NoiseGyro", "gyroscope", "noise_density"), ("IMU.NoiseAcc", "accelerometer", "noise_density"),
        ("IMU.GyroWalk", "gyroscope", "random_walk"), ("IMU.AccWalk", "accelerometer", "random_walk"))


def write(inputs) -> Export:
    cal, noise = inputs.calibration, inputs.noise
    inflate = float(inputs.option("inflate", 1.0))
    lines = ["%YAML:1.0", f"# ORB-SLAM3 IMU settings from accelcal (noise: {noise.get('source')}); paste into your "
             "settings file",
             "# continuous-time densities and random walks (ORB-SLAM3 scales them by sqrt(IMU.Frequency))"]
    for key, sensor, what in KEYS:
        v = noise_value(noise, sensor, what, "ORB-SLAM3", inflate)
        if v is None:
            raise ExportError(f"ORB-SLAM3 needs the noise of both sensors; the noise report has no {sensor}")
        lines.append(f"{key}: {v.value:.6e}  # {v.comment}")
    lines.append(f"IMU.Frequency: {noise_rate(noise):.6g}  # [ Hz ] the noise recording's rate: use your IMU's")
    return Export({"": "\n".join(lines) + "\n"}, intrinsics_left_out(cal, "ORB-SLAM3"), [APPLY_FIRST])


__all__ = ["KEYS", "write"]
