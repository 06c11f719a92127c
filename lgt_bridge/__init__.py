"""lgt_bridge: Lie group integration of absolute-coordinate multibody models."""
from .errors import ChartDomainError, InputError, LGTError, StepError
from .plugins import wrap
from .simulate import SimulationResult, simulate  # binds the function over the submodule name
from .simulation import Simulation

__version__ = "0.1.0"
__all__ = ["LGTError", "InputError", "ChartDomainError", "StepError", "wrap", "simulate",
           "SimulationResult", "Simulation"]
