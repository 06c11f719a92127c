"""Integrators of the bridge: RKMK (fixed and adaptive), scipy through τ, generalized-α."""
from .tableaux import ADAPTIVE, FIXED

METHODS = tuple(FIXED) + tuple(ADAPTIVE) + ("genalpha",)

__all__ = ["METHODS"]
