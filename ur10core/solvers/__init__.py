"""Inverse kinematics of the course's other arms, one module per family (docs/kinematics.md §7.3).

* :mod:`.spherical_wrist`: arms whose last three axes meet in a wrist centre, solved by
  Pieper's decoupling: the articulated arms (KUKA KR210, the elbow arm), the Stanford arm and
  the cylindrical arm with a wrist.
* :mod:`.planar`: the planar elbow, the SCARA and the cylindrical arm.
* :mod:`.numerical`: damped least squares from many starts, for any DH table.

A solver takes validated poses (N, 4, 4) and hints (N, n) or None and returns the arrays
of an :class:`ur10core.branches.IKSolution` for N poses; the arm adds its joint limits.
"""
