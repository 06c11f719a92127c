"""Pinocchio models for the adapter tests, built as Pinocchio users build them."""
import numpy as np
import pinocchio as pin


def ball_chain():
    """Free-flyer root, a spherical joint (rotation-only body) and a hinge."""
    m = pin.Model()
    r = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    m.appendBodyToJoint(r, pin.Inertia(2.0, np.array([0, 0, 0.1]), np.diag([1.0, 1.5, 2.0])), pin.SE3.Identity())
    b = m.addJoint(r, pin.JointModelSpherical(), pin.SE3(np.eye(3), np.array([0.3, 0, 0])), "ball")
    m.appendBodyToJoint(b, pin.Inertia(0.5, np.array([0.2, 0, 0]), np.diag([0.1, 0.2, 0.25])), pin.SE3.Identity())
    c = m.addJoint(b, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.4, 0, 0])), "hinge")
    m.appendBodyToJoint(c, pin.Inertia(0.3, np.array([0.15, 0, 0]), np.diag([0.02, 0.05, 0.05])), pin.SE3.Identity())
    return m


def four_bar():
    """Pinocchio's closed-chain example (examples/simulation-closed-kinematic-chains.py) without
    its shapes: three RY links (B1, A2, B2) on a fixed link A1, closed to the world by a 3-D
    RigidConstraintModel (a planar four-bar closed by a 3-D loop: one row is redundant).
    Returns (model, constraint_model)."""
    height, width = 0.1, 0.01
    mass_A, length_A, mass_B, length_B = 10.0, 1.0, 5.0, 0.6
    inertia_A = pin.Inertia.FromBox(mass_A, length_A, width, height)
    center_A = pin.SE3.Identity()
    center_A.translation = pin.XAxis * length_A / 2
    inertia_B = pin.Inertia.FromBox(mass_B, length_B, width, height)
    center_B = pin.SE3.Identity()
    center_B.translation = pin.XAxis * length_B / 2
    model = pin.Model()
    p1 = pin.SE3.Identity()
    p1.translation = pin.XAxis * length_A / 2
    j1 = model.addJoint(0, pin.JointModelRY(), p1, "link_B1")
    model.appendBodyToJoint(j1, inertia_B, center_B)
    p2 = pin.SE3.Identity()
    p2.translation = pin.XAxis * length_B
    j2 = model.addJoint(j1, pin.JointModelRY(), p2, "link_A2")
    model.appendBodyToJoint(j2, inertia_A, center_A)
    p3 = pin.SE3.Identity()
    p3.translation = pin.XAxis * length_A
    j3 = model.addJoint(j2, pin.JointModelRY(), p3, "link_B2")
    model.appendBodyToJoint(j3, inertia_B, center_B)
    c1 = pin.SE3.Identity()
    c1.translation = pin.XAxis * length_B
    c2 = pin.SE3.Identity()
    c2.translation = -pin.XAxis * length_A / 2
    cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, j3, c1, 0, c2)
    return model, cm


#: the closed-chain example's own start on pin 4.1: its inverse-geometry loop (written for
#: pin 3's ContactCholeskyDecomposition) does not close the loop there, and q_sol =
#: (q + π) % π - π of what it reaches is (residual 0.98 m)
FOUR_BAR_EXAMPLE_Q0 = np.array([-1.00626281, -2.60202803, -2.28698983])


def parallelogram_q(theta):
    """A closed configuration of the four-bar on its parallelogram branch (crank angle θ
    below the horizontal): (θ, π - θ, θ)."""
    return np.array([theta, np.pi - theta, theta])
