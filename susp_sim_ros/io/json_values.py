"""JSON encoding of what the analyses return: numpy scalars and arrays as plain numbers and lists."""
from __future__ import annotations

import numpy as np


def jsonable(x):
    """``json.dump(..., default=jsonable)``: a numpy scalar as its Python number, an array as a (nested)
    list, anything else as its string."""
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)
