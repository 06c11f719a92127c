"""Bench scenes of the Pinocchio adapter with the user loops of
:mod:`lgt_pinocchio.baselines` as native baselines; q is Pinocchio's own configuration
vector throughout.

* ``pinocchio_free_body``, ``pinocchio_humanoid``: the free asymmetric body and
  ``buildSampleModelHumanoidRandom`` (no extra packages).
* ``pinocchio_robot:NAME`` (``--scenario free|pd``): any free-flyer robot of the
  ``example-robot-data-loaders`` package (``pip install 'lgt-bridge[robots]'``), NAME as
  ``example_robot_data.load(NAME)`` takes it (solo12, go2, anymal, talos, ...), loaded
  with its reference configuration ``robot.q0`` (the loader reads it from the robot's SRDF,
  e.g. "standing" or "half_sitting"; neutral where there is none) and Pinocchio's gravity.
  See :data:`SCENARIOS` and :func:`robot_state` for the state and the gains.
"""
import functools
import warnings

import numpy as np

from lgt_bridge.bench import BenchScene, SceneFamily
from lgt_bridge.errors import InputError

from . import baselines as _b
from .model import PinocchioModel

#: end time of the robot scenes (s)
T_ROBOT = 1.0
#: initial base twist of the robot scenes in Pinocchio's order and (body) frame:
#: v_lin (m/s), ω (rad/s): thrown up and sideways, tumbling about all three axes
BASE_TWIST = (0.3, 0.0, 1.0, 1.0, 2.0, 0.5)
#: joint velocities at t = 0: JOINT_SPEED · N(0, 1) rad/s, seed JOINT_SEED
JOINT_SPEED, JOINT_SEED = 0.5, 0
#: PD stiffness (N·m/rad, every actuated joint) and damping ratio of the pd scenario
KP, ZETA = 1000.0, 1.0
INSTALL = "pip install 'lgt-bridge[robots]' (the example-robot-data-loaders package)"

SCENARIOS = {
    "free": "tumbling free fall, zero joint torque",
    "pd": (f"PD control toward the loader's q0 on every actuated joint, τ = kp (q0 - q) - kd v, "
           f"kp = {KP:g} N·m/rad, kd_j = {2 * ZETA:g}·√(kp·M_jj(q0)) (critical damping of joint j alone; "
           "M_jj: diagonal of Pinocchio's CRBA at q0, armature included)"),
}
STATE = (f"from the loader's q0, base twist v = {BASE_TWIST[:3]} m/s, ω = {BASE_TWIST[3:]} rad/s (body "
         f"frame), joint velocities {JOINT_SPEED:g}·N(0, 1) rad/s (seed {JOINT_SEED}), gravity on, "
         f"{T_ROBOT:g} s")


def _scene(make, T, euler_dts, rk4_dts, tols, about, tau=None):
    """``make() -> (pin model, q0, v0)``; ``tau``: None or ``make_tau() -> tau(t, q, v)``
    for both the PinocchioModel and the user loops."""
    def model():
        m, q0, v0 = make()
        t = None if tau is None else tau()
        return PinocchioModel(m, q0=q0, v0=v0, tau=t, tau_derivatives=getattr(t, "derivatives", None))

    def native(loop):
        def run(setting):
            m, q0, v0 = make()
            kw = {} if tau is None else dict(tau=tau())
            with np.errstate(all="ignore"):         # a loop past its stability limit overflows
                q, n = loop(m, q0, v0, T, setting, **kw)
            return dict(q=q, n_f=n, n_steps=None if loop is _b.dop853_renorm else int(round(T / setting)))
        return run
    natives = {"semi-implicit Euler + pin.integrate": ("dt", euler_dts, native(_b.semi_implicit_euler)),
               "RK4 + renormalization": ("dt", rk4_dts, native(_b.rk4_renorm)),
               "DOP853 + renormalization": ("tol", tols, native(_b.dop853_renorm))}
    return BenchScene(model, T, natives, about)


# --- robots of example-robot-data ---------------------------------------------------------------
def _loaders():
    """example_robot_data.robots_loader, or an InputError saying what to install."""
    try:
        from example_robot_data import robots_loader
    except ImportError:
        raise InputError(f"bench pinocchio_robot:NAME loads robots with example_robot_data: {INSTALL}.") from None
    return robots_loader


def free_flyer_robots():
    """Names of the robots whose loader builds a free-flyer root (InputError without the
    loaders). Some of them still cannot run here; the scene says why when it is built."""
    return sorted(n for n, cls in _loaders().ROBOTS.items() if getattr(cls, "free_flyer", False))


def floated(name):
    """True when robot ``name``'s loader fixes its base (``load_robot(..., floating=True)``
    then gives it a free-flyer root)."""
    return not getattr(_loaders().ROBOTS[name], "free_flyer", False)


def check_robot(name, floating=False):
    """InputError unless ``name`` is a free-flyer robot of the installed loaders, or with
    ``floating`` any of their robots (nothing is loaded)."""
    robots = _loaders().ROBOTS
    if name not in robots:
        raise InputError(f"bench pinocchio_robot: unknown robot {name!r}; example_robot_data's free-flyer "
                         f"robots: {', '.join(free_flyer_robots())}.")
    if not floating and not getattr(robots[name], "free_flyer", False):
        raise InputError(f"bench pinocchio_robot: robot {name!r} has a fixed base (its loader builds no "
                         f"free-flyer root joint); use a free-flyer robot: {', '.join(free_flyer_robots())}.")


@functools.lru_cache(maxsize=None)
def load_robot(name, continuous=False, floating=False):
    """(pin.Model, q0) of robot ``name`` as ``example_robot_data.load(name)`` gives them
    (q0: the loader's reference configuration), loaded once per process; the model is shared,
    not to be modified. ``continuous``: also robots with continuous joints (q = (cos θ, sin θ);
    the free-fall scenario's loops renormalize them); the PD controller needs nq = nv.
    ``floating``: a robot whose loader fixes its base (a mobile manipulator such as tiago) is
    built with a free-flyer root, by the loader's own ``free_flyer`` switch."""
    check_robot(name, floating)
    import example_robot_data as erd
    cls = _loaders().ROBOTS[name]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if getattr(cls, "free_flyer", False):
                robot = erd.load(name)
            else:
                robot = type(cls.__name__, (cls,), {"free_flyer": True})().robot
    except Exception as exc:            # the loader's own failure (a version check, a missing file)
        raise InputError(f"bench pinocchio_robot: example_robot_data.load({name!r}) failed: "
                         f"{type(exc).__name__}: {' '.join(str(exc).split())}") from None
    m = robot.model
    if m.njoints < 2 or m.joints[1].shortname() != "JointModelFreeFlyer":
        raise InputError(f"bench pinocchio_robot: robot {name!r} loaded without a free-flyer root joint; "
                         f"use one of {', '.join(free_flyer_robots())}.")
    for j in range(2, m.njoints):
        jm = m.joints[j]
        if jm.nq != jm.nv and not (continuous and jm.nq == 2 and jm.nv == 1):
            raise InputError(f"bench pinocchio_robot: robot {name!r} has joint {m.names[j]!r}, a {jm.shortname()} "
                             f"(nq = {jm.nq}, nv = {jm.nv}: a URDF continuous joint); the pd scenario's "
                             "controller needs joints with nq = nv after the free-flyer (revolute, prismatic); "
                             "the free scenario runs it. PinocchioModel itself runs it too: wrap the model and "
                             "call simulate.")
    return m, np.array(robot.q0, float)


def robot_state(name, floating=False):
    """(pin.Model, q0, v0) of the robot scenes: the loader's q0, v0 = BASE_TWIST on the
    root and JOINT_SPEED·N(0, 1) (seed JOINT_SEED) on the joints (``floating``: as
    :func:`load_robot`)."""
    m, q0 = load_robot(name, continuous=True, floating=floating)
    rng = np.random.default_rng(JOINT_SEED)
    v0 = np.concatenate([BASE_TWIST, JOINT_SPEED * rng.normal(size=m.nv - 6)])
    return m, q0.copy(), v0


def pd_gains(model, q0):
    """(kp, kd) per actuated joint (size nv - 6) of the pd scenario: kp = KP,
    kd_j = 2 ZETA √(kp M_jj(q0)), M = Pinocchio's CRBA at q0 (armature included)."""
    import pinocchio as pin
    M = pin.crba(model, model.createData(), q0)
    mjj = np.diag(M)[6:]
    kp = np.full(model.nv - 6, KP)
    return kp, 2.0 * ZETA * np.sqrt(kp * mjj)


def pd_controller(name):
    """tau(t, q, v) of the pd scenario for robot ``name`` (:func:`baselines.pd_torque`)."""
    m, q0 = load_robot(name)
    kp, kd = pd_gains(m, q0)
    return _b.pd_torque(m, q0, kp, kd)


def robot_scene(name):
    """The BenchScene of ``pinocchio_robot:NAME``, its scenarios "free" (default) and "pd".
    Checks the name (InputError: unknown, fixed base, loaders missing) without loading."""
    check_robot(name)

    def make():
        return robot_state(name)
    label = f"example-robot-data {name}"
    free = _scene(make, T_ROBOT, [1e-3, 4e-4, 1e-4], [1e-2, 4e-3, 1e-3], [1e-6, 1e-8, 1e-10],
                  f"{label}, {SCENARIOS['free']}, {STATE}")
    pd = _scene(make, T_ROBOT, [1e-3, 2.5e-4, 1e-4], [1e-3, 4e-4, 1e-4], [1e-6, 1e-8, 1e-10],
                f"{label}, {SCENARIOS['pd']}, {STATE}", tau=lambda: pd_controller(name))
    free.scenarios = {"free": free, "pd": pd}
    return free


def bench_scenes():
    return {
        "pinocchio_free_body": _scene(_b.free_body, 10.0, [1e-2, 4e-3, 1e-3], [1e-2, 4e-3, 1e-3],
                                      [1e-6, 1e-8, 1e-10],
                                      "free asymmetric body (Pinocchio free-flyer), 10 s"),
        "pinocchio_humanoid": _scene(_b.humanoid, 1.0, [1e-3, 4e-4, 1e-4], [4e-2, 1e-2, 4e-3],
                                     [1e-6, 1e-8, 1e-10],
                                     "buildSampleModelHumanoidRandom floating under gravity, 1 s"),
        "pinocchio_robot": SceneFamily(
            robot_scene, arg="NAME", scenarios=SCENARIOS,
            about=("a free-flyer robot of example-robot-data, NAME as example_robot_data.load takes it "
                   f"(solo12, go2, anymal, talos, ...; pip install 'lgt-bridge[robots]'), {STATE}")),
    }
