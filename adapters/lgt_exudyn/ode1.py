"""Exudyn's ODE1 coordinates (first-order states: controllers, filters, hydraulics) carried
by an :class:`lgt_exudyn.ExudynModel` alongside its ODE2 part.

Each y_i, ẏ = Exudyn's ODE1 right-hand side, is the *rate* of a vector-space pair appended
to the state: V gets the n1 entries y (V̇_y = ẏ) and q gets n1 entries that hold ∫y dt,
which nothing reads; so every method integrates y with the rest of the state
(generalized-α as its trapezoidal-like update of a rate). The ODE2 part sees its own
entries q[:n2], V[:nv], with y written into Exudyn before each evaluation (ODE2 forces may
depend on it).
"""
import numpy as np

from lgt_bridge.errors import InputError
from lgt_bridge.model import Layout


class ODE1States:
    """The ODE1 part of a system (``engine``: :class:`.engine.Engine`) appended to the ODE2
    layout ``layout2`` and initial state (q0, V0): ``layout``, ``q0``, ``V0`` of the whole
    state."""

    def __init__(self, engine, layout2, q0, V0):
        sd, mbs = engine.sd, engine.mbs
        self.engine = engine
        self.n1 = n1 = sd.ODE1Size()
        self.ref1 = np.zeros(n1)        # Exudyn's system vector of ODE1 references is empty
        for i in range(sd.NumberOfNodes()):
            try:
                idx = list(sd.GetNodeLTGODE1(i))
            except Exception:                  # nodes without ODE1 coordinates
                continue
            if idx:
                self.ref1[idx] = np.ravel(mbs.GetNode(i).get("referenceCoordinates", np.zeros(len(idx))))
        y0 = np.array(sd.GetODE1Coordinates()) + self.ref1
        n2, nv = self.n2, self.nv = layout2.nq, layout2.nv
        self.layout = Layout(n2 + n1, nv + n1, layout2.bodies, layout2.vector_q + tuple(range(n2, n2 + n1)),
                             layout2.vector_v + tuple(range(nv, nv + n1)))
        self.q0 = np.concatenate([q0, np.zeros(n1)])
        self.V0 = np.concatenate([V0, y0])
        if not np.isfinite(y0).all():
            raise InputError("Exudyn initial ODE1 coordinates are not finite; fix the ODE1 nodes' "
                             "initialCoordinates.")

    def write(self, V):
        """Write y = V[nv:] into Exudyn."""
        self.engine.sd.SetODE1Coordinates(np.asarray(V[self.nv:], float) - self.ref1)

    def with_rates(self, x):
        """x (the ODE2 part's V̇ or Q̄) followed by ẏ, Exudyn's ODE1 right-hand side at the
        written state."""
        E = self.engine
        E.solver.ComputeODE1RHS(E.mbs)
        ydot = np.array(E.solver.GetSystemResidual())[self.n2:self.n2 + self.n1]
        return np.concatenate([x, ydot])

    def mass_matrix(self, M):
        """The whole state's mass matrix from the ODE2 part's M (the ODE1 block: identity)."""
        out = np.eye(self.nv + self.n1)
        out[:self.nv, :self.nv] = M
        return out

    def solve_mass(self, solve2, B):
        """M⁻¹ B of the whole state from ``solve2`` (the ODE2 part's M⁻¹)."""
        B = np.asarray(B, float)
        out = B.copy()
        out[:self.nv] = solve2(B[:self.nv])
        return out

    def jacobian(self, A):
        """The constraint Jacobian of the whole state from the ODE2 part's A (y is free)."""
        return np.hstack([A, np.zeros((A.shape[0], self.n1))])
