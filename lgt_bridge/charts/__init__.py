"""Charts ψ as data: one :class:`~.base.Chart` object per chart, covering SE(3),
SO(3)xR³ and SO(3) (rotation-only bodies).

    exp    exponential coordinates                       (:mod:`.exp`)
    cay    Cayley map, Gibbs vectors                      (:mod:`.cay`)
    cay2   second-order Cayley map, Wiener–Milenkovic     (:mod:`.cay2`)

A chart is chosen by name (``get("cay2")``); adding one is a module here with its maps
and its increment, an entry in :data:`CHARTS`, and its branch in ``kernels/charts.py``.
"""
import numpy as np

from ..errors import InputError
from .base import GROUPS, Chart, GroupMaps
from .cay import CAY
from .cay2 import CAY2
from .exp import EXP

#: every chart by name, in kernel-code order
CHARTS = {c.name: c for c in sorted((EXP, CAY, CAY2), key=lambda c: c.code)}
NAMES = tuple(CHARTS)

#: 1/limit per kernel code (0 for an unbounded chart): the kernels' domain guard
INV_LIMITS = np.array([0.0 if not c.bounded else 1.0 / c.limit for c in CHARTS.values()])


def get(chart):
    """The :class:`Chart` named ``chart`` (a Chart passes through)."""
    if isinstance(chart, Chart):
        return chart
    try:
        return CHARTS[chart]
    except (KeyError, TypeError):
        raise InputError(f"unknown chart {chart!r}; use one of {list(CHARTS)}.") from None


def check_chart(chart):
    """The chart's name, or InputError listing the valid ones."""
    return get(chart).name


__all__ = ["Chart", "GroupMaps", "GROUPS", "CHARTS", "NAMES", "INV_LIMITS", "get", "check_chart",
           "EXP", "CAY", "CAY2"]
