"""ur10core — the UR10 kinematics the teaching app is built on.

The course's conventions, equations and worked examples are written up in the project's
``docs/kinematics.md``; each function says which section it implements.

``BACKEND`` says which kernels run: ``"compiled"`` (the C accelerator, built where a C
compiler was available at install time) or ``"numpy"`` (everywhere; forced with the
environment variable ``UR10CORE_BACKEND=numpy``). Both give the same results.

>>> from ur10core import Arm, to_controller, from_controller
>>> arm = Arm.preset("course")
>>> BACKEND in ("compiled", "numpy")
True
"""

from ._backend import BACKEND
from .arm import DH_ALPHA, JOINT_LIMIT, JOINT_NAMES, Arm, SingularityGeometry
from .controller import (
    CONTROLLER_OFFSET,
    FLANGE_TURN,
    flange_from_controller,
    flange_to_controller,
    from_controller,
    to_controller,
)
from .ik import (
    ELBOW_TOO_CLOSE,
    ELBOW_TOO_FAR,
    REACHABLE,
    SLOT_LABELS,
    SLOTS,
    WRIST_INSIDE_CYLINDER,
    Branch,
    IKSolution,
    Slot,
    nearest_branch,
)

__all__ = [
    "Arm",
    "BACKEND",
    "Branch",
    "CONTROLLER_OFFSET",
    "DH_ALPHA",
    "ELBOW_TOO_CLOSE",
    "ELBOW_TOO_FAR",
    "FLANGE_TURN",
    "IKSolution",
    "JOINT_LIMIT",
    "JOINT_NAMES",
    "REACHABLE",
    "SLOTS",
    "SLOT_LABELS",
    "SingularityGeometry",
    "Slot",
    "WRIST_INSIDE_CYLINDER",
    "flange_from_controller",
    "flange_to_controller",
    "from_controller",
    "nearest_branch",
    "to_controller",
]
