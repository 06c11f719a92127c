"""Bench scenes of the Pinocchio adapter (``lgt-bridge bench pinocchio_free_body``,
``pinocchio_humanoid``) with the user loops of :mod:`lgt_pinocchio.baselines` as
native baselines. q is Pinocchio's own configuration vector in both."""
from lgt_bridge.bench import BenchScene

from . import baselines as _b
from .model import PinocchioModel


def _scene(make, T, euler_dts, rk4_dts, tols, about):
    def model():
        m, q0, v0 = make()
        return PinocchioModel(m, q0=q0, v0=v0)

    def native(loop):
        def run(setting):
            m, q0, v0 = make()
            q, n = loop(m, q0, v0, T, setting)
            return dict(q=q, n_f=n, n_steps=None if loop is _b.dop853_renorm else int(round(T / setting)))
        return run
    natives = {"semi-implicit Euler + pin.integrate": ("dt", euler_dts, native(_b.semi_implicit_euler)),
               "RK4 + renormalization": ("dt", rk4_dts, native(_b.rk4_renorm)),
               "DOP853 + renormalization": ("tol", tols, native(_b.dop853_renorm))}
    return BenchScene(model, T, natives, about)


def bench_scenes():
    return {
        "pinocchio_free_body": _scene(_b.free_body, 10.0, [1e-2, 4e-3, 1e-3], [1e-2, 4e-3, 1e-3],
                                      [1e-6, 1e-8, 1e-10],
                                      "free asymmetric body (Pinocchio free-flyer), 10 s"),
        "pinocchio_humanoid": _scene(_b.humanoid, 1.0, [1e-3, 4e-4, 1e-4], [4e-2, 1e-2, 4e-3],
                                     [1e-6, 1e-8, 1e-10],
                                     "buildSampleModelHumanoidRandom floating under gravity, 1 s"),
    }
