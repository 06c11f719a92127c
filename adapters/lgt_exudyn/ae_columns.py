"""The algebraic equations' rows of Exudyn's system Jacobian, ∂C/∂q (and ∂C/∂q + ∂C/∂q̇ with
velocity-level rows), from their velocity-level residual, for large systems
(:meth:`.engine.Engine.ae_jacobian_full`).

Exudyn hands its system Jacobian to Python only whole and dense: on a belt of 128 ANCF cables
(527 unknowns) ``GetSystemJacobian`` alone took 2.4 ms, and the constraint rows of an index-1
evaluation (zeroing the matrix, ``ComputeJacobianAE``, reading it back) 2.5 ms, about 2.4 times
per f. Holonomic constraints' velocity-level residual is affine in the velocities,
C_q(q) q̇ + C_t, so its difference at q̇ = Σ e_j and at q̇ = 0 is the sum of C_q's columns j,
exact up to rounding (no truncation). Columns that share no constraint row (a greedy colouring
of the constraints' structural pattern: each object's AE rows against its ODE2 coordinates) are
probed together, a few evaluations of ``ComputeAlgebraicEquations`` in all.

Taken only where it agrees with Exudyn's own Jacobian at the first state asked (:meth:`check`:
to 1e-12 of its largest entry, the pattern holding every nonzero), so a constraint whose
velocity-level equation is not C_q q̇ (or not affine in q̇) keeps Exudyn's dense Jacobian.
"""
import numpy as np

#: systems with at least this many unknowns (ODE2 + ODE1 + AE) take the rows by columns
MIN_UNKNOWNS = 200
#: agreement with Exudyn's Jacobian required, relative to its largest AE entry
CHECK = 1e-12


def structural_pattern(engine, velocity_rows=False):
    """(rows, cols) of the AE rows' possible nonzeros: each object with algebraic equations,
    its AE rows against its ODE2 coordinates (system row and column indices). Objects whose
    equation is at velocity level (``velocityLevel``: a drive q̇ᵢ = c) take part only with
    ``velocity_rows`` (the Jacobian asked is ∂C/∂q + ∂C/∂q̇: theirs is ∂g/∂q̇ when g does not
    depend on q); in ∂C/∂q alone Exudyn leaves their rows zero."""
    sd, ae0, mbs = engine.sd, engine.ae0, engine.mbs
    rows, cols = [], []
    for k in range(sd.NumberOfObjects()):
        try:
            ae = np.asarray(sd.GetObjectLTGAE(k), np.int64)
            if not len(ae) or (not velocity_rows and mbs.GetObject(k).get("velocityLevel", False)):
                continue
            ode2 = np.asarray(sd.GetObjectLTGODE2(k), np.int64)
        except Exception:                      # objects without algebraic equations
            continue
        rows.append(np.repeat(ae + ae0, len(ode2)))
        cols.append(np.tile(ode2, len(ae)))
    if not rows:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(rows), np.concatenate(cols)


class AEColumns:
    """Probes of the velocity-level AE residual giving the AE rows of the system Jacobian."""

    def __init__(self, engine, rows, cols):
        self.engine = engine
        keep = {}
        for r, c in zip(rows.tolist(), cols.tolist()):
            keep.setdefault(c, set()).add(r)
        groups, used = [], []                  # greedy colouring: no shared row within a group
        for c in sorted(keep):
            for g, u in zip(groups, used):
                if not (u & keep[c]):
                    g.append(c)
                    u |= keep[c]
                    break
            else:
                groups.append([c])
                used.append(set(keep[c]))
        self.groups = [np.array(g, np.int64) for g in groups]
        group_of = {c: i for i, g in enumerate(groups) for c in g}
        entry_group = np.array([group_of[c] for c in cols.tolist()], np.int64)
        # per group, its entries' (rows, cols)
        self.entries = [(rows[entry_group == i], cols[entry_group == i]) for i in range(len(groups))]
        n = engine.ae0 + engine.nae
        self.out = np.zeros((n, n))            # only the AE rows' entries are written

    def jacobian(self):
        """The system Jacobian with ∂C/∂q on its AE rows (the other rows zero), at the written
        coordinates and time; the written velocities are left as they were."""
        E = self.engine
        S, mbs, sd, n2 = E.solver, E.mbs, E.sd, E.n2
        vel = sd.GetODE2Coordinates_t()
        probe = np.zeros(n2)
        sd.SetODE2Coordinates_t(probe)
        S.ComputeAlgebraicEquations(mbs, True)
        r0 = np.array(S.GetSystemResidual())
        out = self.out
        try:
            for g, (rows, cols) in zip(self.groups, self.entries):
                probe[g] = 1.0
                sd.SetODE2Coordinates_t(probe)
                S.ComputeAlgebraicEquations(mbs, True)
                r = np.array(S.GetSystemResidual())
                probe[g] = 0.0
                out[rows, cols] = r[rows] - r0[rows]
        finally:
            sd.SetODE2Coordinates_t(vel)
        return out

    def check(self, exact):
        """True when :meth:`jacobian` equals Exudyn's own ``exact`` (the whole system Jacobian)
        on the AE rows' ODE2 columns, every nonzero of it within the pattern."""
        E = self.engine
        a, n2 = E.ae0, E.n2
        ref = np.array(exact[a:, :n2])
        got = self.jacobian()[a:, :n2]
        scale = max(float(np.abs(ref).max(initial=0.0)), 1e-300)
        return bool(np.abs(got - ref).max(initial=0.0) <= CHECK * scale)
