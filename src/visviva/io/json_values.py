"""Values as plain JSON: what run summaries, sweep tables and the CLI's ``--json`` print.

Apart from :mod:`~visviva.io.job`, and without importing NumPy, so that a command printing plain
data (``visviva schema``) does not import the recordings and the numerical stack behind them.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from typing import Any

__all__ = ["plain_json"]


def plain_json(value: Any) -> Any:
    """``value`` as plain JSON: NumPy scalars unwrapped, non-finite floats as strings."""
    if isinstance(value, Mapping):
        return {str(k): plain_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_json(v) for v in value]
    # A NumPy scalar exists only once NumPy is imported; plain data never needs to import it.
    numpy = sys.modules.get("numpy")
    if numpy is not None and isinstance(value, numpy.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
