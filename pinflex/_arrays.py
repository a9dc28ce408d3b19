"""Small array helpers shared by the dataclasses of pinflex."""

from __future__ import annotations

import numpy as np


def readonly(values) -> np.ndarray:
    """A read-only float copy of ``values`` (fields of frozen dataclasses)."""
    array = np.array(values, dtype=float)
    array.setflags(write=False)
    return array
