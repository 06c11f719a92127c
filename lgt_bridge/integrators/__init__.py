"""Integrators of the bridge: RKMK (fixed and adaptive), Radau IIA, scipy through τ,
generalized-α; the methods' table is :mod:`.registry`."""
from .registry import METHODS

__all__ = ["METHODS"]
