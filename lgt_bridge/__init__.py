"""lgt_bridge: Lie group integration of absolute-coordinate multibody models."""
from .errors import ChartDomainError, InputError, LGTError, StepError

__version__ = "0.1.0"
__all__ = ["LGTError", "InputError", "ChartDomainError", "StepError"]
