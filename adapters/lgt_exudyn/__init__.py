"""lgt_exudyn: Exudyn models on lgt_bridge's Lie group integrators, unchanged.

    from lgt_exudyn import ExudynModel, SolveDynamic
"""
from .model import ExudynModel
from .solve import SolveDynamic

__all__ = ["ExudynModel", "SolveDynamic"]
