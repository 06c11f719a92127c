"""lgt_pinocchio: Pinocchio free-flyer models on lgt_bridge's Lie group integrators.

    from lgt_pinocchio import PinocchioModel
"""
from .model import PinocchioModel

__all__ = ["PinocchioModel"]
