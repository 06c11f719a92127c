"""A run's last step when f jumps in time exactly at the end time.

A load switched on at the end time (``np.heaviside(t - t_end, 1)`` in a user function) is
seen by every step landing there: its last stage sits at t_end, on the far side of the
jump, so at a tight tolerance the error control rejects each such step down to the
run's smallest step. The motion up to t_end does not depend on f at the single instant
t_end (the state is continuous; only the accelerations jump), so the run takes its last
step to the double just below t_end, where every stage is on the near side of the jump,
and ends at t_end with that state: the left limit, which is what a run of the model up to
t_end means. The state moves by |V| times one rounding unit of t over that last gap.

:func:`finish_left_of_jump` is called (by :func:`collapsed`) when the steps collapse below
``min_step`` within the last millionth of the run (:func:`.diagnosis.jump_size_at_end` says
whether f jumps there); ``Simulation.end_jump`` then holds the size of the jump it stepped
around, and the result's ``stats["end_jump"]`` reports it.
"""
import numpy as np

from .diagnosis import jump_size_at_end, step_too_small


def collapsed(sim, on_step):
    """The run's step fell below ``min_step``: it ends at its left limit when f jumps at the
    end time (:func:`finish_left_of_jump`), else fails (:func:`.diagnosis.step_too_small`)."""
    if not finish_left_of_jump(sim, on_step):
        raise step_too_small(sim)


def finish_left_of_jump(sim, on_step):
    """End the run at ``sim.t_end`` with a last step to the double just below it, when f
    jumps at the end time (see the module). True when the run has reached the end time,
    False when this does not apply (no jump there, mode switches or a post-step hook, a
    fixed-step method, or the step to the left limit is itself rejected)."""
    st, t1 = sim.stepper, sim.t_end
    if (t1 is None or not st.adaptive or sim._post is not None or sim._switches is not None):
        return False
    d = jump_size_at_end(sim)
    if d is None:
        return False
    t_left = float(np.nextafter(t1, -np.inf))
    accepted, _ = st.attempt(sim.t, t_left - sim.t)
    if not accepted:
        return False
    sim.n_steps += 1
    sim.t = t1
    st.restart_at(st.q, st.V, t1)        # the last stage's f is the near side's: not the next step's
    sim.end_jump = d
    sim.model.write_back(st.q, st.V, t1)
    if on_step is not None:
        on_step(t1, st.q, st.V)
    return True
