"""``simulate``: run a model on a bridge integrator and collect the result (one
:class:`~lgt_bridge.simulation.Simulation`, set up and run once)."""
from .lgt import DEFAULT_GROUP
from .result import SimulationResult
from .simulation import Simulation, make_stepper
from .validation import check_inputs


def simulate(model, t_span, *, method="rkmk4", group=DEFAULT_GROUP, chart="exp", dt=None, rtol=1e-6,
             atol=1e-8, q0=None, V0=None, t_eval=None, progress=None, max_steps=1_000_000,
             project=True, rho_inf=0.9, newton_tol=1e-10, events=None, max_step=None):
    """Integrate ``model`` over ``t_span`` with a Lie group method through τ.

    method: "euler", "rkmk2", "rkmk4" (fixed dt), "dopri5", "dop853" (adaptive: rtol/atol,
    dt = first step), "scipy:<Name>" (scipy solver inside macro steps of length dt),
    "radau5" (implicit Radau IIA of order 5, adaptive: rtol/atol, dt = first step; for stiff
    models such as PD-controlled robots), "genalpha" (fixed dt, index-3 constraints,
    numerical damping ``rho_inf``).
    group: "SO3xR3" (default), "SE3" or "auto"; chart: "exp", "cay", "cay2" (second-order Cayley:
    up to 240° per stage) or "auto" (one value or one per body). "auto" picks per body what the model's structure needs
    (:mod:`lgt_bridge.auto`); ``stats["auto"]`` says what it chose and why, and
    ``result.group``/``result.chart`` hold the resolved per-body lists.
    Constrained models with explicit methods are projected onto g = 0 and A V = b
    after every step, and an initial state that violates the constraints is projected
    before the first step (``stats["initial_projection"]`` says how far it moved);
    ``project=False`` turns both off.
    t_eval: output times; default: every step. Fixed-step methods land on them;
    dopri5, dop853 and radau5 interpolate them with their continuous extension (through τ),
    so output times never shorten their steps.
    progress: None (default) shows a tqdm bar on stderr (simulated time, steps, f
    evaluations, current step size, rate) once the run has taken more than about 1 s,
    and only when stderr is a terminal and the environment variable ``CI`` is unset;
    True always shows it, False never (:mod:`lgt_bridge.progress`).
    max_step: the largest step an adaptive method (dopri5, dop853, radau5) may take (None,
    the default: no cap); a load acting for a short time is then never stepped over.
    max_steps: the most accepted steps the run may take (default 10⁶); reaching it ends
    the run with ``success = False`` and a message saying so, keeping the steps computed.
    events: a function g(t, q, V) -> float or a list of them (scipy's convention: attributes
    ``terminal`` (bool or a count), ``direction`` (-1, 0, +1)); each zero crossing is located on
    the step's continuous extension through τ (fixed-step methods: a cubic Hermite interpolant
    of (X, W) within the step) and returned in ``t_events``, ``q_events``, ``V_events``; a
    terminal event ends the run at its time with the model written back there
    (``success=True``, the message names the event). See :mod:`lgt_bridge.events`.
    """
    t0, t1, q0, V0, t_eval = check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval,
                                          max_steps)
    sim = Simulation(model, method=method, group=group, chart=chart, dt=dt, rtol=rtol, atol=atol,
                     t0=t0, t_end=t1, q0=q0, V0=V0, max_steps=max_steps, project=project,
                     rho_inf=rho_inf, newton_tol=newton_tol, max_step=max_step, checked=True)
    return sim.run(t1, t_eval, progress, events)


__all__ = ["simulate", "SimulationResult", "Simulation", "make_stepper"]
