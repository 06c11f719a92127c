"""The drop-in's outputs: the states at Exudyn's step ends, evaluated from the bridge's
dense output a step at a time (:class:`OutputRows`), and which of Exudyn's engine
quantities its outputs read between steps (:func:`outputs_read`)."""
import numpy as np


class OutputRows:
    """The states at Exudyn's step ends (its output times). When a bridge step covers
    several of them, they are evaluated in one dense-output call
    (:meth:`lgt_bridge.Simulation.advance_to_many`) and handed out one per Exudyn step.
    Exudyn's step ends are predicted as its loop accumulates them (t + h, one addition per
    step); a time that differs from the prediction (Exudyn's last step, shortened to end on
    endTime) is evaluated on its own, so each state is the one at Exudyn's own time."""

    def __init__(self, sim, t_end, step_size):
        self.sim, self.t_end, self.step_size = sim, t_end, step_size      # step_size(): Exudyn's h
        self.t, self.Q, self.V, self.i = (), None, None, 0
        self.written = False

    def at(self, target, on_step):
        """(q, V) at Exudyn's step end ``target``; ``written`` says whether it is the state a
        bridge step just ended on at ``target`` (the driver wrote it into the system)."""
        sim = self.sim
        if not sim.dense:               # fixed steps: each Exudyn step ends on a bridge step
            n = sim.n_steps
            q, V = sim.advance_to(target, on_step)
            self.written = sim.n_steps > n and sim.t == target
            return q, V
        self.written = False
        i = self.i
        if i < len(self.t) and self.t[i] == target:
            self.i = i + 1
            return self.Q[i], self.V[i]
        h = self.step_size()
        # the Exudyn steps the next bridge step may cover (sim.h: its proposed length)
        m = max(1, min(int((self.t_end - target) / h) + 1, int(sim.h / h) + 2))
        if m == 1:
            times = np.array([target])
        else:
            times = np.full(m, h)
            times[0] = target
            times = np.add.accumulate(times)
        n, self.Q, self.V = sim.advance_to_many(times, on_step)
        self.t, self.i = times[:n].tolist(), 1
        return self.Q[0], self.V[0]


#: sensors that read only positions, velocities and rotations of what they name (unless
#: their output variable is an acceleration); loads read their own values
_KINEMATIC_SENSORS = ("Node", "Marker", "Body", "Load")


def outputs_read(mbs, settings):
    """{"accelerations": ..., "multipliers": ...}: whether an output reads the engine's
    accelerations / Lagrange multipliers between steps: the solution file exporting them,
    a sensor of an acceleration, a sensor of an object (joint forces) or a user-function
    or other sensor (which may read either)."""
    sol = settings.solution
    export = sol.file.export
    acc = bool(sol.file.write and export.accelerations)
    lam = bool(sol.file.write and export.algebraicCoordinates)
    for i in range(mbs.systemData.NumberOfSensors()):
        sensor = mbs.GetSensor(i)
        kind = sensor.get("outputVariableType")
        if "Acceleration" in getattr(kind, "name", str(kind)):
            acc = True
        if sensor.get("sensorType") not in _KINEMATIC_SENSORS:
            acc = lam = True
    return {"accelerations": acc, "multipliers": lam}
