"""Input checks shared by every public entry point.

Each helper raises :class:`~visviva.errors.ModelError` with a message that names the argument,
the value received and what would be accepted, so that the caller's traceback ends in a sentence
a user can act on.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .errors import ModelError

__all__ = ["describe", "real_number", "state_array", "whole_number"]


def describe(value: Any) -> str:
    """``value`` as the user would write it, shortened: NumPy scalars print as plain numbers."""
    if isinstance(value, np.generic):
        value = value.item()
    elif isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list) and len(value) > 6:
        text = repr(value[:6])[:-1] + ", ...]"
    else:
        text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def with_article(noun: str) -> str:
    """``noun`` after "a" or "an": ``with_article("ellipsoid")`` is "an ellipsoid"."""
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


def real_number(
    name: str,
    value: Any,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    unit: str = "",
) -> float:
    """Return ``value`` as a finite float, or raise naming ``name``.

    Args:
        name: Argument name used in the message, e.g. ``"dt"``.
        value: The value to check (bools are refused: ``True`` is not a time step).
        positive: Require ``value > 0``.
        nonnegative: Require ``value >= 0``.
        unit: Unit appended to the requirement in the message, e.g. ``" s"``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(
            f"`{name}` must be a real number{unit and ' in' + unit} (got {describe(value)})"
        )
    try:
        number = float(value)
    except OverflowError:
        raise ModelError(
            f"`{name}` must be finite (got {describe(value)}, beyond the range of a float)"
        ) from None
    if not math.isfinite(number):
        raise ModelError(f"`{name}` must be finite (got {number!r})")
    if positive and not number > 0.0:
        raise ModelError(f"`{name}` must be positive{unit and ', in' + unit} (got {number!r})")
    if nonnegative and number < 0.0:
        raise ModelError(f"`{name}` must be zero or positive (got {number!r})")
    return number


def whole_number(name: str, value: Any, *, minimum: int = 0) -> int:
    """Return ``value`` as an int ≥ ``minimum``, or raise naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ModelError(f"`{name}` must be a whole number (got {describe(value)})")
    if value < minimum:
        raise ModelError(f"`{name}` must be at least {minimum} (got {int(value)})")
    return int(value)


def state_array(name: str, value: Any) -> np.ndarray:
    """Return a read-only float64 (or complex128) copy of a state array, checked finite.

    Scalars become shape ``(1,)``; the last axis is the coordinate axis, an optional leading
    axis is the batch axis. More than two axes is refused.
    """
    try:
        array = np.array(value, copy=True)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ModelError(f"`{name}` must be an array of numbers (got {describe(value)})") from exc
    if array.dtype == object or not (
        np.issubdtype(array.dtype, np.number) or array.dtype == np.bool_
    ):
        raise ModelError(f"`{name}` must be an array of numbers (got {describe(value)})")
    dtype = np.complex128 if np.iscomplexobj(array) else np.float64
    array = np.atleast_1d(array.astype(dtype))
    if array.ndim > 2:
        raise ModelError(
            f"`{name}` must have shape (n,) for one system or (batch, n) for a batch "
            f"(got shape {array.shape})"
        )
    if array.size == 0:
        raise ModelError(f"`{name}` must not be empty (got shape {array.shape})")
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        where = index[0] if len(index) == 1 else index
        raise ModelError(f"`{name}` must be finite; entry {where} is {describe(array[index])}")
    array.setflags(write=False)
    return array
