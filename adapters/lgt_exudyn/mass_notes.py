"""The refusal text for an Exudyn model whose mass matrix the bridge cannot invert
(``ExudynModel.check_mass_matrix``): what the defect is and what to do, including the object
kinds whose Exudyn mass matrix is singular whatever the user gives them."""
from lgt_bridge.validation import mass_message, more_directions


def singular_mass_text(mbs, defects, owners, held):
    """InputError text for the mass-matrix ``defects`` (velocity index, scaled eigenvalue)
    named by ``owners``; ``held``: M is positive definite on the motions the constraints
    allow, singular only in directions they hold (Exudyn runs such a model, the bridge's
    solves, which invert M itself, cannot)."""
    if held:
        return _held_text(defects, owners) + _ale_hint(mbs, owners)
    if any("ObjectANCFBeam " in o for o in owners):
        # its cross-section slopes: rank 3 of 6 in M, whatever sectionData.inertia
        fix = (" Exudyn's ObjectANCFBeam has such a mass matrix whatever its sectionData: three "
               "directions of the slope coordinates of each node carry no inertia. Run it with "
               "Exudyn's own exu.SolveDynamic (generalized-α: its iteration matrix includes the "
               "stiffness), or use ObjectBeamGeometricallyExact.")
    else:
        fix = (" Exudyn's implicit solvers (generalized-α) can run such a model, since their "
               "iteration matrix includes the stiffness; run it with Exudyn's own "
               "exu.SolveDynamic, or give these coordinates mass (an ANCF cable's or beam's "
               "inertia: no zero entry).")
    return mass_message(defects, owners) + fix


def _held_text(defects, owners):
    i, lam = defects[0]
    more = more_directions(defects, owners)
    return (f"mass matrix at q0 is singular: a motion led by {owners[0]} (velocity index {i}) "
            f"carries no kinetic energy (scaled eigenvalue {lam:.2g}){more}. The model's constraints "
            "hold that motion (the mass matrix is positive definite on the motions they allow), so "
            "Exudyn's own solvers, whose iteration matrix contains the constraint Jacobian, run the "
            "model; lgt_bridge's solves invert the mass matrix itself and cannot. Run it with "
            "Exudyn's own exu.SolveDynamic.")


def _ale_hint(mbs, owners):
    """ObjectALEANCFCable2D with physicsMovingMassFactor = 1: all of the cable's mass moves with
    the ALE coordinate, so along a straight cable an ALE motion and an axial motion of the
    cable have the same kinetic energy (a factor below 1 makes M regular)."""
    if not any("ObjectALEANCFCable2D" in o for o in owners):
        return ""
    whole = []
    for k in range(mbs.systemData.NumberOfObjects()):
        obj = mbs.GetObject(k)
        if obj.get("objectType") == "ALEANCFCable2D" and obj.get("movingMassFactor", 0.0) == 1.0:
            whole.append(k)
    if not whole:
        return ""
    listed = ", ".join(str(k) for k in whole[:8]) + (", ..." if len(whole) > 8 else "")
    return (f" Its ObjectALEANCFCable2D {listed} have physicsMovingMassFactor = 1: all of a cable's "
            "mass moves with the ALE coordinate, so along a straight cable an ALE motion and an axial "
            "motion of the cable carry the same kinetic energy. With a factor below 1 (the part of "
            "the mass that does not move with the ALE coordinate, a pipe's own mass) the mass matrix "
            "is regular and lgt_bridge runs the model.")
