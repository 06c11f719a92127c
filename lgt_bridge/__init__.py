"""lgt_bridge: Lie group integration of absolute-coordinate multibody models."""
from .errors import ChartDomainError, InputError, LGTError, StepError
from .plugins import wrap

__version__ = "0.1.0"
__all__ = ["LGTError", "InputError", "ChartDomainError", "StepError", "wrap", "simulate"]


def __getattr__(name):
    if name == "simulate":
        from .simulate import simulate
        return simulate
    raise AttributeError(name)
