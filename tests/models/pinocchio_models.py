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
