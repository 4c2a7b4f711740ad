"""One conversion of results to what JSON can hold.

Results carry numpy arrays and scalars, tuples, and NaN where a quantity is not
estimable.  :func:`json.dump` rejects the numpy types and writes NaN as the token ``NaN``,
which is not JSON (strict parsers, JavaScript, ``jq`` refuse it).  Every JSON file the
library, the command line and the workflow write goes through :func:`json_safe` first.
"""

from __future__ import annotations

import math

import numpy as np


def json_safe(obj):
    """``obj`` with plain Python types only, and None for every non-finite number.

    Parameters
    ----------
    obj
        Nested dicts, lists, tuples, numpy arrays and scalars, numbers, strings, None.

    Returns
    -------
    object
        The same structure with dicts (keys as strings), lists (for tuples and arrays),
        ``bool``, ``int``, ``float`` (finite) or None (NaN and ±inf), and every other value
        as it was.

    Examples
    --------
    >>> json_safe({"bias": np.array([0.1, np.nan]), "n": np.int64(3), "ok": np.bool_(True)})
    {'bias': [0.1, None], 'n': 3, 'ok': True}
    """
    if isinstance(obj, dict):
        return {k if isinstance(k, str) else str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def is_finite(x) -> bool:
    """Whether ``x``, a number or the None that :func:`json_safe` writes for a quantity not
    estimable, is a finite number."""
    return x is not None and math.isfinite(x)


__all__ = ["is_finite", "json_safe"]
