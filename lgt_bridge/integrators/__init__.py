"""Integrators of the bridge: RKMK (fixed and adaptive), Radau IIA, scipy through τ,
generalized-α."""
from .tableaux import ADAPTIVE, FIXED

METHODS = tuple(FIXED) + tuple(ADAPTIVE) + ("radau5", "genalpha")

__all__ = ["METHODS"]
