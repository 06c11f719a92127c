"""Bench scenes of the Exudyn adapter, with Exudyn's own solvers as native baselines:

* ``exudyn_heavy_top`` — the example heavy top (EP node, spherical joint), 0.5 s;
  natives: generalized-α on EP nodes and on RotVecLG nodes (Lie group, simplified
  kinematic relations), steps from 2000 to 128000.
* ``exudyn_chain`` — 10 links on spherical joints, 1 s; the same natives.
* ``exudyn_free_bodies`` — 8 torque-free bodies on RotVecLG nodes, 2 s; natives:
  Exudyn's explicit Lie group DOPRI5 (C++, adaptive) and RK44.

Native runs on RotVecLG nodes are compared after converting their rotations to the
scene model's coordinates (through the unit quaternion).
"""
import exudyn as exu
import numpy as np

from lgt_bridge.bench import BenchScene

from . import scenes as _s
from .model import ExudynModel


def convert_q(src, q, dst):
    """q of model ``src`` in the coordinates of model ``dst`` (same bodies in the same
    order; rotations through the unit quaternion, other coordinates copied)."""
    out = np.array(dst.q0, float)
    for a, b in zip(src.layout.bodies, dst.layout.bodies):
        out[list(b.pos)] = q[list(a.pos)]
        p = a.param.to_quat(q[list(a.rot)])
        out[list(b.rot)] = b.param.from_quat(p, out[list(b.rot)])
    out[list(dst.layout.vector_q)] = q[list(src.layout.vector_q)]
    return out


def _ga(build, T, node):
    def run(n):
        _, mbs = build(node)[:2]
        s = _s.settings(T, int(n))
        if node == _s.ROTVEC:
            s.timeIntegration.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
        mbs.SolveDynamic(s)
        q = _s.total_q(mbs)
        if node != _s.EP:
            q = convert_q(ExudynModel(mbs), q, ExudynModel(build(_s.EP)[1]))
        return dict(q=q, n_f=None, n_steps=int(n))
    return run


def _explicit(build, T, solver, adaptive):
    def run(setting):
        _, mbs = build()[:2]
        # Exudyn caps an adaptive step at endTime / numberOfSteps: 1 lets the tolerance act
        s = _s.settings(T, 1 if adaptive else int(setting))
        ti = s.timeIntegration                    # 'explicit' replaces 'explicitIntegration' in newer Exudyn
        (ti.explicit if hasattr(ti, "explicit") else ti.explicitIntegration).useLieGroupIntegration = True
        if adaptive:
            s.timeIntegration.automaticStepSize = True
            s.timeIntegration.absoluteTolerance = setting
            s.timeIntegration.relativeTolerance = setting
            s.timeIntegration.minimumStepSize = 1e-12
        else:
            s.timeIntegration.automaticStepSize = False
        mbs.SolveDynamic(s, solverType=solver)
        return dict(q=_s.total_q(mbs), n_f=None, n_steps=None if adaptive else int(setting))
    return run


def bench_scenes():
    def top(node):
        return _s.heavy_top(node)

    def chain(node):
        return _s.chain(10, node)

    ga_steps = [2000, 8000, 32000, 128000]
    out = {}
    for name, build, T, steps, about in (
            ("exudyn_heavy_top", top, 0.5, ga_steps, "Exudyn heavy top, EP node + spherical joint, 0.5 s"),
            ("exudyn_chain", chain, 1.0, [250, 1000, 4000, 16000], "Exudyn chain of 10 links, spherical joints, 1 s")):
        out[name] = BenchScene(lambda build=build: ExudynModel(build(_s.EP)[1]), T,
                               {"Exudyn generalized-α, EP": ("n", steps, _ga(build, T, _s.EP)),
                                "Exudyn generalized-α, RotVecLG": ("n", steps, _ga(build, T, _s.ROTVEC))},
                               about)
    T = 2.0
    out["exudyn_free_bodies"] = BenchScene(
        lambda: ExudynModel(_s.free_bodies()[1]), T,
        {"Exudyn DOPRI5, RotVecLG": ("tol", [1e-5, 1e-7, 1e-9, 1e-11],
                                     _explicit(_s.free_bodies, T, exu.DynamicSolverType.DOPRI5, True)),
         "Exudyn RK44, RotVecLG": ("n", [200, 800, 3200], _explicit(_s.free_bodies, T,
                                                                     exu.DynamicSolverType.RK44, False))},
        "8 torque-free bodies on Exudyn RotVecLG nodes, 2 s")
    return out
