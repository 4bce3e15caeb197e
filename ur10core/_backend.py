"""Which implementation of the kernels runs: the compiled one, or numpy.

``UR10CORE_BACKEND=numpy`` forces numpy (the compiled module is then not even imported,
as on a laptop without a C compiler); ``UR10CORE_BACKEND=compiled`` insists on the
compiled kernel (an ``ImportError`` if it was not built). Unset: compiled when it is
there, which it is wherever a C compiler was available at install time.
"""

from __future__ import annotations

import os
from types import ModuleType

from . import _numpy_kernels, tolerances


def configured(module: ModuleType) -> ModuleType:
    """``module`` (either kernel) handed the values of :mod:`ur10core.tolerances`, its one source."""
    module.set_tolerances(
        tolerances.LENGTH_TOLERANCE,
        tolerances.CHOICE_TOLERANCE,
        tolerances.WRIST_TURN_TOLERANCE,
        tolerances.WRIST_TOLERANCE,
        tolerances.ROTATION_TOLERANCE,
        tolerances.BOTTOM_ROW_TOLERANCE,
        tolerances.BAND_LEVERAGE,
        tolerances.REACH_ROUNDING,
        tolerances.SIDE_TOLERANCE,
        tolerances.STRETCHED_TOLERANCE,
        tolerances.LIMIT_TOLERANCE,
        tolerances.SQUARE_ROUNDING,
    )
    return module


_REQUESTED = os.environ.get("UR10CORE_BACKEND", "").strip().lower()
if _REQUESTED not in ("", "compiled", "numpy"):
    raise ImportError(f"UR10CORE_BACKEND must be 'compiled' or 'numpy', got {_REQUESTED!r}")

kernels = _numpy_kernels
if _REQUESTED != "numpy":
    try:
        from . import _kernels as kernels  # type: ignore[no-redef]
    except ImportError:
        if _REQUESTED == "compiled":
            raise
kernels = configured(kernels)

#: ``"compiled"`` or ``"numpy"``.
BACKEND = "numpy" if kernels is _numpy_kernels else "compiled"
