"""The methods: one table, name -> :class:`Method` (what it is and how to build it).

Everything that asks what a method is — ``simulate``, the Exudyn drop-in, ``auto``, the
bench and the CLI — reads this table; a method's name appears here and in its own module,
nowhere else. A method is built lazily (its module is imported on first use), so
``import lgt_bridge`` stays light.

Properties:

- ``steps``: "fixed" (takes ``dt``), "adaptive" (error control by rtol/atol; ``dt`` is the
  first trial step) or "macro" (scipy's solvers: adaptive inside macro steps of ``dt``);
- ``implicit``; ``dense`` (a continuous extension: output times never shorten steps);
- ``constraints``: "projected" (after each step, by :class:`.constraints.Projector`) or
  "index3" (the method solves the position constraints itself);
- ``order``; ``fixed_form``: an adaptive pair that can also run fixed steps of its own
  tableau (Exudyn's ``automaticStepSize=False``).

How to add a method: write its stepper (the contract is :class:`.base.Stepper`) with a
``build(method, problem, options)`` function in its module, and add a row below.
"""
from dataclasses import dataclass
from importlib import import_module

from ..errors import InputError

#: scipy.integrate.solve_ivp's methods run through τ (``scipy:<Name>``)
SCIPY = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")
_SCIPY_IMPLICIT = ("Radau", "BDF", "LSODA")


@dataclass(frozen=True)
class Method:
    name: str
    builder: str                 # "module:function" under lgt_bridge.integrators
    steps: str                   # "fixed", "adaptive" or "macro"
    order: int
    summary: str
    implicit: bool = False
    dense: bool = False
    constraints: str = "projected"
    fixed_form: bool = False

    @property
    def adaptive(self):
        return self.steps == "adaptive"

    @property
    def fixed(self):
        return self.steps == "fixed"

    @property
    def uses_tolerances(self):
        return self.steps in ("adaptive", "macro")

    @property
    def projects(self):
        """Constraints are enforced by projection after each step (not by the method)."""
        return self.constraints == "projected"

    def build(self, problem, *, dt=None, rtol=1e-6, atol=1e-8, projector=None, rho_inf=0.9,
              newton_tol=1e-10, fixed_steps=False):
        """The stepper of this method on ``problem``. ``fixed_steps``: an adaptive pair with
        a fixed form runs fixed steps of its own tableau."""
        build = _BUILDERS.get(self.builder)
        if build is None:
            module, fn = self.builder.split(":")
            build = _BUILDERS[self.builder] = getattr(import_module(f"{__package__}.{module}"), fn)
        return build(self, problem, dict(dt=dt, rtol=rtol, atol=atol, projector=projector,
                                         rho_inf=rho_inf, newton_tol=newton_tol,
                                         fixed_steps=fixed_steps))


#: "module:function" -> the builder, imported on first use
_BUILDERS = {}

_TABLE = (
    Method("euler", "rkmk:build", "fixed", 1, "Lie–Euler (RKMK of order 1)"),
    Method("rkmk2", "rkmk:build", "fixed", 2, "RKMK Heun (explicit trapezoidal rule)"),
    Method("rkmk4", "rkmk:build", "fixed", 4, "RKMK classical Runge–Kutta"),
    Method("dopri5", "rkmk:build", "adaptive", 5, "Dormand–Prince 5(4), PI step control",
           dense=True, fixed_form=True),
    Method("dop853", "rkmk:build", "adaptive", 8, "Hairer's DOP853, 5th/3rd-order error estimate",
           dense=True, fixed_form=True),
    Method("radau5", "radau:build", "adaptive", 5,
           "Radau IIA (implicit, L-stable) with simplified Newton, for stiff models",
           implicit=True, dense=True),
    Method("genalpha", "genalpha:build", "fixed", 2,
           "Lie group generalized-α (index 3, numerical damping rho_inf)", implicit=True,
           constraints="index3"),
)

#: the bridge's own methods by name
METHODS = {m.name: m for m in _TABLE}


def _scipy(name):
    return Method(f"scipy:{name}", "vector_space:build", "macro", 0,
                  f"scipy.integrate.solve_ivp's {name} on the local ODE inside macro steps of dt",
                  implicit=name in _SCIPY_IMPLICIT)


def names():
    """Every method name, scipy's as ``scipy:<Name>``."""
    return list(METHODS) + [f"scipy:{n}" for n in SCIPY]


def choices_text():
    """The method names for messages and help: 'euler, ..., genalpha or scipy:<Name> with ...'."""
    return f"{', '.join(METHODS)} or scipy:<Name> with Name in {', '.join(SCIPY)}"


def get(method):
    """The :class:`Method` called ``method``; InputError naming the valid ones."""
    if isinstance(method, Method):
        return method
    if method in METHODS:
        return METHODS[method]
    if isinstance(method, str) and method.startswith("scipy:"):
        if method[6:] in SCIPY:
            return _scipy(method[6:])
        raise InputError(f"unknown scipy method {method[6:]!r}; use one of {list(SCIPY)}.")
    raise InputError(f"unknown method {method!r}; use one of {list(METHODS)} or "
                     f"'scipy:<Name>' with Name in {list(SCIPY)}.")


def by(**props):
    """The bridge's methods whose properties equal ``props`` (e.g. ``by(steps="fixed")``)."""
    return [m.name for m in _TABLE if all(getattr(m, k) == v for k, v in props.items())]
