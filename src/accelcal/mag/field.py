"""The local geomagnetic field from a place and a date (IGRF, through the ``geomag`` extra's
``ppigrf``): the strength the calibrated field is scaled to, and the dip it is checked against."""

from __future__ import annotations

import datetime as dt
import math

from ..errors import AccelcalError, MissingExtraError


def parse_location(text: str) -> tuple[float, float, float]:
    """``'LAT,LON[,ALT_KM]'`` -> (lat, lon, alt_km), checked."""
    try:
        v = [float(x) for x in str(text).split(",")]
    except ValueError:
        v = []
    if len(v) not in (2, 3) or not all(math.isfinite(x) for x in v):
        raise AccelcalError(f"--location must be LAT,LON[,ALT_KM] in degrees (and km), got {text!r}")
    lat, lon, alt = v[0], v[1], v[2] if len(v) == 3 else 0.0
    if not (-90 <= lat <= 90 and -180 <= lon <= 360 and -1 < alt < 1000):
        raise AccelcalError(f"--location: latitude in [-90, 90], longitude in [-180, 360], altitude in km; got {text!r}")
    return lat, lon, alt


def parse_date(text: str) -> dt.datetime:
    try:
        return dt.datetime.strptime(str(text).strip(), "%Y-%m-%d")
    except ValueError:
        raise AccelcalError(f"--date must be YYYY-MM-DD, got {text!r}") from None


def model_field(location: str, date: str) -> dict:
    """``{'strength': µT, 'unit': 'uT', 'dip_deg', 'declination_deg', 'source'}`` of the IGRF."""
    lat, lon, alt = parse_location(location)
    when = parse_date(date)
    try:
        import ppigrf
    except ImportError:
        raise MissingExtraError("--location/--date need the IGRF model of the 'geomag' extra: "
                                "pip install 'accelcal[geomag]' (or leave them out: the field is then normalised "
                                "to its fitted strength)") from None
    try:
        be, bn, bu = (float(x) for x in (c.ravel()[0] for c in ppigrf.igrf(lon, lat, alt, when)))
    except Exception as e:  # the model's own range check (a date outside its epochs)
        raise AccelcalError(f"--date {date}: the IGRF model cannot evaluate it ({e})") from None
    horizontal = math.hypot(be, bn)
    return {"strength": math.sqrt(be * be + bn * bn + bu * bu) / 1000.0, "unit": "uT",
            "dip_deg": math.degrees(math.atan2(-bu, horizontal)), "declination_deg": math.degrees(math.atan2(be, bn)),
            "source": f"IGRF (ppigrf) at {lat:g},{lon:g},{alt:g} km on {when.date()}"}


__all__ = ["model_field", "parse_date", "parse_location"]
