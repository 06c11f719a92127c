"""Exudyn access of :class:`lgt_exudyn.ExudynModel`: the evaluator (Exudyn's implicit solver
object set up to write no files and no sensors), state writes, the algebraic equations'
residual and Jacobian, and Exudyn's exceptions turned into ModelErrors."""
import contextlib
import functools
import re

import numpy as np

from lgt_bridge.errors import LGTError, ModelError


_OWN_FRAME = re.compile(r"\s*\[Python file '[^']*(?:lgt_exudyn|lgt_bridge)[^']*', line \d+\]")


def exudyn():
    import exudyn
    return exudyn


def engine_error(sd, what, exc):
    """The ModelError for an exception Exudyn raised while ``what`` evaluated the model (a
    user function that failed, an evaluation Exudyn rejects), or None when ``exc`` is not
    Exudyn's (a bug: it keeps its traceback). ``sd``: the system's data (for the time)."""
    if not type(exc).__module__.startswith("exudyn"):
        return None
    text = str(exc).split("\nAt:")[0]           # Exudyn appends a traceback after "At:"
    lines = [ln.strip() for ln in text.strip().splitlines() if ln.strip()]
    msg = " ".join(lines) if lines else type(exc).__name__
    # Exudyn names the Python frame running when the user function failed: the bridge's
    # own file, not the user's; drop that pointer (the user function's name stays)
    msg = _OWN_FRAME.sub("", msg)
    if len(msg) > 300:
        msg = msg[:300] + "..."
    t, stop = sd.GetTime(), "" if msg.endswith((".", "!", "?")) else "."
    return ModelError(f"Exudyn raised while lgt_bridge evaluated the model ({what}) at "
                      f"t = {t:.9g}: {msg}{stop} If a user function failed, "
                      "fix it (run the script with Exudyn's own solver to see it in context).")


def guarded_f(plain, sd):
    """The model's f from the kernels' closure ``plain(q, V, t)``: its arguments made float64
    C-contiguous and a float, Exudyn's exceptions turned into the ModelError of
    :func:`engine_error`; ``f.loop_f`` the same for the compiled step loop, which passes its
    arguments in that form already (its result a float64 vector: no check)."""
    contiguous = np.ascontiguousarray

    def f(q, V, t):
        try:
            return plain(contiguous(q, float), contiguous(V, float), float(t))
        except Exception as exc:
            err = engine_error(sd, "f", exc)
            if err is None:
                raise
            raise err from exc

    def loop_f(q, V, t):
        try:
            return plain(q, V, t)
        except Exception as exc:
            err = engine_error(sd, "f", exc)
            if err is None:
                raise
            raise err from exc
    f.loop_f, loop_f.returns_float64_vector = loop_f, True
    return f


@contextlib.contextmanager
def engine_errors(sd, what):
    """Within: an exception Exudyn raises becomes the ModelError of :func:`engine_error`
    (the original chained: ``--debug`` shows it); the bridge's own errors and bugs pass."""
    try:
        yield
    except LGTError:
        raise
    except Exception as exc:
        err = engine_error(sd, what, exc)
        if err is None:
            raise
        raise err from exc


def engine_call(method):
    """Turn an exception Exudyn raises inside ``method`` (of an object with ``sd``) into a
    ModelError naming the time and Exudyn's message (:func:`engine_errors`)."""
    name = method.__name__

    @functools.wraps(method)
    def call(self, *args, **kwargs):
        # engine_errors written out: this wraps every evaluation of the step loop (the
        # projection's, the drop-in's output writes), where the context manager's generator
        # cost about a microsecond per call
        try:
            return method(self, *args, **kwargs)
        except LGTError:
            raise
        except Exception as exc:
            err = engine_error(self.sd, name, exc)
            if err is None:
                raise
            raise err from exc
    return call


def engine_set_up(init):
    """``init(self, mbs, ...)`` reading a model: a user function Exudyn calls meanwhile (a
    constraint's offset user function in the Jacobian, ...) that fails is a ModelError."""
    @functools.wraps(init)
    def call(self, mbs, *args, **kwargs):
        with engine_errors(mbs.systemData, "set-up"):
            return init(self, mbs, *args, **kwargs)
    return call


class Engine:
    """An assembled system and its evaluator. ``ref``: Exudyn's reference ODE2 coordinates
    (q, the bridge's, is reference + current); ``ae0``: the first AE row of Exudyn's
    system vectors and Jacobian."""

    def __init__(self, mbs):
        exu = self.exu = exudyn()
        self.mbs, self.sd = mbs, mbs.systemData
        sd = self.sd
        self.n2, self.nae = sd.ODE2Size(), sd.AEsize()
        self.solver = exu.MainSolverImplicitSecondOrder()
        s = self.settings = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.show.computationTime = False
        s.show.statistics = False
        # the bridge computes its own initial accelerations; Exudyn's would fail (with a
        # warning) on redundant constraints
        s.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
        self.solver.InitializeSolver(mbs, s)
        self.ref = np.array(sd.GetODE2Coordinates(exu.ConfigurationType.Reference))
        self.ae0 = self.solver.GetODE2size() + self.solver.GetODE1size()
        self.jac_zero = np.zeros((self.ae0 + self.nae, self.ae0 + self.nae))
        # the AE Jacobians by columns (ae_columns), by (c_pos, c_vel): absent untried, False dense
        self._ae_columns = {}

    def write(self, q, qd, t):
        """Exudyn's state: coordinates q - ref, velocities qd, time t."""
        sd = self.sd
        sd.SetODE2Coordinates(q - self.ref)
        sd.SetODE2Coordinates_t(qd)
        sd.SetTime(t)

    def mass_matrix(self):
        """Exudyn's ODE2 mass matrix at the written state (a copy)."""
        self.solver.ComputeMassMatrix(self.mbs)
        return np.array(self.solver.GetSystemMassMatrix())

    def ae_jacobian(self, c_pos=1.0, c_vel=1.0):
        """Exudyn's AE Jacobian at the written state: c_pos ∂C/∂q + c_vel ∂C/∂q̇ (all AE
        rows, n2 columns) and the AE-AE diagonal (1 on rows Exudyn keeps as λ = 0)."""
        J = self.ae_jacobian_full(c_pos, c_vel)
        a = self.ae0
        return np.array(J[a:, :self.n2]), np.diagonal(J[a:, a:]).copy()

    def ae_jacobian_full(self, c_pos, c_vel):
        """Exudyn's whole system Jacobian (a view) holding c_pos ∂C/∂q + c_vel ∂C/∂q̇ on its AE
        rows, at the written coordinates. ∂C/∂q of a large system comes from the columns of
        the velocity-level residual (:mod:`.ae_columns`) where they agree with Exudyn's."""
        key = (c_pos, c_vel) if c_pos == 1.0 and c_vel in (0.0, 1.0) else None
        cols = self._ae_columns.get(key) if key is not None else False
        if cols:
            return cols.jacobian()
        S = self.solver
        S.SetSystemJacobian(self.jac_zero)
        S.ComputeJacobianAE(self.mbs, c_pos, c_vel, 0.0, False)
        J = S.GetSystemJacobian()
        if cols is None:
            self._ae_columns[key] = self._probe_columns(J, c_vel == 1.0)
        return J

    def _probe_columns(self, exact, velocity_rows):
        """An :class:`.ae_columns.AEColumns` when it agrees with ``exact`` (Exudyn's Jacobian
        at the written state), else False (Exudyn's dense Jacobian from then on)."""
        from . import ae_columns
        if self.ae0 + self.nae < ae_columns.MIN_UNKNOWNS or not self.nae:
            return False
        rows, cols = ae_columns.structural_pattern(self, velocity_rows)
        if not len(rows):
            return False
        probe = ae_columns.AEColumns(self, rows, cols)
        try:
            ok = probe.check(exact)
        except Exception:                       # a residual Exudyn will not evaluate so: dense
            ok = False
        return probe if ok else False

    def ae_residual(self, q, qd, t, velocity_level, rows):
        """Exudyn's algebraic equations' residual (``velocity_level``: their velocity form)
        at (q, qd, t), AE rows ``rows``."""
        self.write(q, qd, t)
        self.solver.ComputeAlgebraicEquations(self.mbs, velocity_level)
        return np.array(self.solver.GetSystemResidual())[self.ae0:][rows]

    def ae_owners(self, rows):
        """'object k 'name' (TypeName)' for each object owning one of the AE ``rows``."""
        sd, names = self.sd, []
        for k in range(sd.NumberOfObjects()):
            try:
                ltg = set(sd.GetObjectLTGAE(k))
            except Exception:                       # objects without algebraic equations
                continue
            if ltg & set(rows):
                o = self.mbs.GetObject(k)
                names.append(f"object {k} {o.get('name', '')!r} ({o.get('objectType', '?')})")
        return ", ".join(names) or "unknown objects"
