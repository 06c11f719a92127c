"""Exceptions raised on purpose by lgt_bridge.

Every error derives from :class:`LGTError` and its message says what was wrong,
where (argument, body index, time) and what to do about it.
"""


class LGTError(Exception):
    """Base class of every error lgt_bridge raises on purpose."""


class InputError(LGTError, ValueError):
    """Bad input rejected before any computation: wrong shape, NaN/inf, a
    non-unit quaternion, an unknown option, an inconsistent time span."""


class ChartDomainError(LGTError, ValueError):
    """A local chart is evaluated outside its domain (e.g. the Cayley chart at a
    half-turn, where the Gibbs vector does not exist)."""


class StepError(LGTError, RuntimeError):
    """An integration step failed (non-finite state, Newton divergence)."""


class ModelNote(UserWarning):
    """Something lgt_bridge noticed about a model and handled, which the user should
    know: redundant constraint equations it set aside, an inconsistent initial state it
    moved onto the constraints."""


class ModelError(LGTError, RuntimeError):
    """The wrapped engine raised while evaluating the model (a user function failed, or
    the engine rejected a state); the message names the time and the engine's message."""
