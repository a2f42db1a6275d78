"""
The types the public API's annotations name.

Triples are per axis (x, y, z) or per actuator (A, B, C); arrays are
numpy's float64, one row per sample; a stamp is ROS's ``(sec, nanosec)``.
"""

import pathlib
from typing import Sequence, Union

import numpy as np
import numpy.typing as npt

Triple = tuple[float, ...]          # a triple returned (three floats)
Array = npt.NDArray[np.float64]     # N samples (x 3)
Vector = Union[Sequence[float], Array]  # a triple given: any three floats
Rows = Union[Array, Sequence[Sequence[float]]]  # N x 3 given
Stamp = tuple[int, int]             # (sec, nanosec)
Path = Union[str, pathlib.Path]
