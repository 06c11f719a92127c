"""``simulate``: run a model on a bridge integrator and collect the result (one
:class:`~lgt_bridge.simulation.Simulation`, set up and run once)."""
from .lgt import DEFAULT_GROUP
from .result import SimulationResult
from .integrators.steppers import release
from .simulation import Simulation, make_stepper
from .validation import check_inputs


def simulate(model, t_span, *, method="rkmk4", group=DEFAULT_GROUP, chart="exp", dt=None, rtol=1e-6,
             atol=1e-8, q0=None, V0=None, t_eval=None, progress=None, max_steps=1_000_000,
             project=True, rho_inf=0.9, newton_tol=1e-10, events=None, max_step=None):
    """Integrate ``model`` over ``t_span`` with a Lie group method through τ.

    Parameters
    ----------
    model : lgt_bridge.model.Model
        The model: an engine adapter's (:func:`lgt_bridge.wrap`, ``ExudynModel``,
        ``PinocchioModel``), an engine-free scene (:mod:`lgt_bridge.scenes`) or your own.
    t_span : (float, float)
        Start and end time, ``t0 < t_end``.
    method : str, default "rkmk4"
        "euler", "rkmk2", "rkmk4" (fixed ``dt``); "dopri5", "dop853" (adaptive: ``rtol``/``atol``,
        ``dt`` = first step); "scipy:<Name>" (a scipy solver inside macro steps of length
        ``dt``); "radau5" (implicit Radau IIA of order 5, adaptive; for stiff models such as
        PD-controlled robots); "genalpha" (fixed ``dt``, index-3 constraints, numerical damping
        ``rho_inf``). The table: :mod:`lgt_bridge.integrators.registry`.
    group : str or list of str, default "SO3xR3"
        "SO3xR3", "SE3" or "auto", one value or one per body. "auto" picks per body what the
        model's structure needs (:mod:`lgt_bridge.auto`); ``stats["auto"]`` says what it chose
        and why, and ``result.group`` / ``result.chart`` hold the resolved per-body lists.
    chart : str or list of str, default "exp"
        "exp", "cay", "cay2" (second-order Cayley: up to 240° per stage) or "auto".
    dt : float, optional
        The step of fixed-step methods (required there), the first step of adaptive ones, the
        macro step of "scipy:<Name>".
    rtol, atol : float, default 1e-6, 1e-8
        Tolerances of the adaptive methods (also the events' time tolerance).
    q0, V0 : ndarray, optional
        Initial state in the model's own coordinates (default: the model's ``q0``, ``V0``).
    t_eval : array_like, optional
        Output times (default: every step; empty: none). Fixed-step methods land on them;
        dopri5, dop853 and radau5 interpolate them with their continuous extension (through
        τ), so output times never shorten their steps.
    progress : bool, optional
        None (default) shows a tqdm bar on stderr (simulated time, steps, f evaluations, current
        step size, rate) once the run has taken more than about 1 s, and only when stderr is a
        terminal and the environment variable ``CI`` is unset; True always, False never
        (:mod:`lgt_bridge.progress`).
    max_steps : int, default 1_000_000
        The most accepted steps the run may take; reaching it ends the run with
        ``success=False`` and a message saying so, keeping the steps computed. An adaptive
        run whose steps have been steady for two budget windows (1000 steps each, fewer when
        steps are slow) and whose rest needs more than 4x the steps left ends there, saying
        why (for an explicit method at its stability limit: that step, from the model's
        Jacobian or Hairer's test, and the advice radau5/genalpha).
    project : bool, default True
        Constrained models with explicit methods are projected onto g = 0 and A V = b after
        every step, and an initial state that violates the constraints is projected before the
        first step (``stats["initial_projection"]`` says how far it moved); False turns both off.
    rho_inf : float, default 0.9
        Spectral radius at infinity of "genalpha" (numerical damping; 1: none).
    newton_tol : float, default 1e-10
        Newton's stopping tolerance of "genalpha", relative to the size of the velocities
        (``newton_tol·(1 + |W|_RMS)`` on the RMS update, never below the rounding floor).
    events : callable or list of callable, optional
        Functions ``g(t, q, V) -> float`` with scipy's attributes ``terminal`` (bool or a
        count) and ``direction`` (-1, 0, +1); each zero crossing is located on the step's
        continuous extension through τ (fixed-step methods: a cubic Hermite interpolant of
        (X, W) within the step). A terminal event ends the run at its time with the model
        written back there. See :mod:`lgt_bridge.events`.
    max_step : float, optional
        The largest step an adaptive method (dopri5, dop853, radau5) may take (None: no cap);
        a load acting for a short time is then never stepped over.

    Returns
    -------
    SimulationResult
        ``t``, ``q`` (the model's own coordinates), ``V``, ``success``, ``message``, ``stats``,
        and ``t_events``, ``q_events``, ``V_events`` (one entry per event function).

    Raises
    ------
    lgt_bridge.InputError
        Bad input (span, options, initial state, events), before any step runs. A step that
        fails later ends the run with ``success=False``, every earlier step kept.

    See Also
    --------
    Simulation : the same run set up once and advanced over consecutive horizons.

    Examples
    --------
    >>> from lgt_bridge import scenes, simulate
    >>> r = simulate(scenes.heavy_top(constrained=True), (0.0, 0.1), method="dop853",
    ...              rtol=1e-8, atol=1e-8)
    >>> r.success, r.q.shape[1]
    (True, 7)
    """
    t0, t1, q0, V0, t_eval = check_inputs(model, t_span, method, dt, rtol, atol, q0, V0, t_eval,
                                          max_steps)
    sim = Simulation(model, method=method, group=group, chart=chart, dt=dt, rtol=rtol, atol=atol,
                     t0=t0, t_end=t1, q0=q0, V0=V0, max_steps=max_steps, project=project,
                     rho_inf=rho_inf, newton_tol=newton_tol, max_step=max_step, checked=True)
    result = sim.run(t1, t_eval, progress, events)
    if events is None:
        release(sim.stepper)         # kept for the next run of this kind (nothing of it is returned)
    return result


__all__ = ["simulate", "SimulationResult", "Simulation", "make_stepper"]
