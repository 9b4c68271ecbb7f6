"""Small file helpers shared by the runners and the CLI: JSON with numpy values and NaN as null, atomically.

Examples
--------
>>> json_safe({"a": float("nan"), "b": [1.0, float("inf")]})
{'a': None, 'b': [1.0, None]}
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np


def json_safe(obj):
    """``obj`` with numpy scalars and arrays as Python values and non-finite floats as ``None``.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, tuples, numbers, strings, numpy values.
    """
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def write_json(path, obj) -> Path:
    """Write ``obj`` (made :func:`json_safe`) as indented JSON atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or Path
        Destination; its directory is created.
    obj : object
        What to write.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(json_safe(obj), indent=2))
    tmp.replace(path)
    return path


def write_text(path, text: str) -> Path:
    """Write ``text`` atomically (temporary file, then rename); the directory is created.

    Parameters
    ----------
    path : str or Path
        Destination.
    text : str
        UTF-8 text.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path
