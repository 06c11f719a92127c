"""The user's loads on a Pinocchio model: joint torques ``tau`` (a vector or ``tau(t, q, v)``),
their Jacobians ``tau_derivatives(t, q, v)`` and external forces ``fext(t, q, v)``, checked
when the model is built and converted to what Pinocchio takes."""
import inspect

import numpy as np

from lgt_bridge.errors import InputError


def check_signature(fn, name, expected):
    """InputError unless ``fn`` can be called with three positional arguments (t, q, v)."""
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):       # builtins without a signature: checked by the first call
        return
    try:
        sig.bind(0.0, None, None)
    except TypeError:
        raise InputError(f"{name}: expected a callable {expected}; {getattr(fn, '__name__', name)}"
                         f"{sig} cannot be called with the three arguments (t, q, v).") from None


class Loads:
    """tau, tau_derivatives and fext of a model with nv velocities and njoints joints (see
    :class:`lgt_pinocchio.PinocchioModel`); ``tau`` is None, a float vector or a callable."""

    def __init__(self, pin, model, tau, fext, tau_derivatives):
        self.pin, self.model, self.nv = pin, model, model.nv
        if callable(tau):
            check_signature(tau, "tau", "tau(t, q, v) returning the joint torques (size nv)")
        if callable(fext):
            check_signature(fext, "fext", "fext(t, q, v) returning one force per joint")
        elif fext is not None:
            raise InputError(f"fext: expected None or a callable fext(t, q, v) returning one force per "
                             f"joint, got a {type(fext).__name__}.")
        if tau_derivatives is not None:
            if not callable(tau):
                raise InputError("tau_derivatives is given but tau is not a callable tau(t, q, v); drop "
                                 "tau_derivatives (a constant tau has none) or pass the controller as tau.")
            check_signature(tau_derivatives, "tau_derivatives",
                            "tau_derivatives(t, q, v) returning (dtau_dq, dtau_dv), each nv x nv")
        if tau is not None and not callable(tau):
            tau = np.asarray(tau, float)
            if tau.shape != (self.nv,) or not np.isfinite(tau).all():
                raise InputError(f"tau: expected a finite vector of size nv = {self.nv} or a callable "
                                 f"tau(t, q, v), got shape {tau.shape}.")
        self.tau, self.fext, self.tau_derivatives = tau, fext, tau_derivatives
        self._data = model.createData() if fext is not None else None     # fext's joint torques

    def check(self, q0, v0):
        """Call each load once at the initial state, so a wrong one fails before any step."""
        self.torques(0.0, q0, v0)
        if self.tau_derivatives is not None:
            self.tau_jacobians(0.0, q0, v0)
        if self.fext is not None:
            self.forces(0.0, q0, v0)

    def torques(self, t, q, v):
        """tau at (t, q, v), a float vector of size nv (zero without tau)."""
        if self.tau is None:
            return np.zeros(self.nv)
        tau = np.asarray(self.tau(t, q, v) if callable(self.tau) else self.tau, float)
        if tau.shape != (self.nv,):
            raise InputError(f"tau(t, q, v) returned shape {tau.shape}; expected ({self.nv},).")
        return tau

    def checked_tau(self, tau):
        """What a tau(t, q, v) returned as a C-contiguous float64 vector of size nv."""
        tau = np.ascontiguousarray(tau, dtype=np.float64)
        if tau.shape != (self.nv,):
            raise InputError(f"tau(t, q, v) returned shape {tau.shape}; expected ({self.nv},).")
        return tau

    def forces(self, t, q, v):
        """fext at (t, q, v) as Pinocchio's ``StdVec_Force`` (checked: one per joint)."""
        pin = self.pin
        fs = self.fext(t, q, v)
        if len(fs) != self.model.njoints:
            raise InputError(f"fext(t, q, v) returned {len(fs)} forces; Pinocchio needs one per joint, "
                             f"model.njoints = {self.model.njoints} (entry 0, the universe, is ignored). "
                             "Pinocchio does not check this itself and would read garbage.")
        if type(fs) is pin.StdVec_Force:
            return fs                                 # already Pinocchio's own container
        out = pin.StdVec_Force()
        for k, f in enumerate(fs):
            if isinstance(f, pin.Force):
                out.append(f)
            else:
                f = np.asarray(f, float)
                if f.shape != (6,) or not np.isfinite(f).all():
                    raise InputError(f"fext: force {k} must be a pinocchio.Force or a finite 6-vector "
                                     f"(linear, angular), got {f!r}.")
                out.append(pin.Force(f[:3], f[3:]))
        return out

    def tau_jacobians(self, t, q, v):
        """(dtau_dq, dtau_dv) from the user's tau_derivatives, checked."""
        try:
            dq, dv = self.tau_derivatives(t, q, v)
        except (TypeError, ValueError) as exc:
            raise InputError(f"tau_derivatives(t, q, v) must return a pair (dtau_dq, dtau_dv): {exc}") from None
        dq, dv = np.asarray(dq, float), np.asarray(dv, float)
        shape = (self.nv, self.nv)
        if dq.shape != shape or dv.shape != shape or not (np.isfinite(dq).all() and np.isfinite(dv).all()):
            raise InputError(f"tau_derivatives(t, q, v) returned arrays of shapes {dq.shape} and {dv.shape}; "
                             f"expected two finite ({self.nv}, {self.nv}) matrices (dtau_dq in Pinocchio's "
                             "tangent coordinates, dtau_dv).")
        return dq, dv

    def joint_torques(self, t, q, v, data=None):
        """The joint torques of fext: Σ_j J_jᵀ f_j (J_j the LOCAL Jacobian of joint j, f_j in its
        frame) = rnea(q, v, 0) - rnea(q, v, 0, fext), on Pinocchio's ``data`` (default: the
        loads' own). How constraintDynamics, which takes no fext, gets the external forces."""
        pin = self.pin
        d = self._data if data is None else data
        z = np.zeros(self.nv)
        return pin.rnea(self.model, d, q, v, z) - pin.rnea(self.model, d, q, v, z, self.forces(t, q, v))

    def generalized(self, t, q, v, data=None):
        """u(t, q, v): tau plus the joint torques of fext (:meth:`joint_torques`)."""
        u = np.array(self.torques(t, q, v), float)
        if self.fext is not None:
            u += self.joint_torques(t, q, v, data)
        return u

    def derivatives(self, t, q, v, u0, data):
        """(∂u/∂q in Pinocchio's tangent coordinates, ∂u/∂v) of :meth:`generalized`: tau's
        from tau_derivatives when given, the rest (fext's joint torques, or a tau without
        derivatives) by forward differences from u0 = u(t, q, v) (2 nv calls per matrix);
        None when u is constant."""
        analytic = self.tau_derivatives is not None
        if (not callable(self.tau) or analytic) and self.fext is None:
            return self.tau_jacobians(t, q, v) if analytic else None
        pin, model, nv = self.pin, self.model, self.nv
        if analytic:                                 # difference fext's part only
            u0 = u0 - self.torques(t, q, v)

        def force(t, q, v):
            u = self.generalized(t, q, v, data)
            return u - self.torques(t, q, v) if analytic else u
        Dq, Dv = np.empty((nv, nv)), np.empty((nv, nv))
        e, vp = np.zeros(nv), v.copy()
        h = 1.5e-8                                   # ≈ √eps: q's tangent is O(1)
        for k in range(nv):
            e[k] = h
            Dq[:, k] = (force(t, pin.integrate(model, q, e), v) - u0) / h
            e[k] = 0.0
            hv = h * max(1.0, abs(v[k]))
            vp[k] = v[k] + hv
            Dv[:, k] = (force(t, q, vp) - u0) / (vp[k] - v[k])
            vp[k] = v[k]
        if analytic:
            dq, dv = self.tau_jacobians(t, q, v)
            Dq += dq
            Dv += dv
        return Dq, Dv
