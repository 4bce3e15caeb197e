"""Speed of the kinematics core beside its references, written to BENCHMARKS.md.

    python benchmarks/bench_core.py

* one-pose IK (all 8 slots) vs ur-analytic-ik's UR10 ``inverse_kinematics`` (C++);
* batch IK of 1 M poses vs the plain numpy vectorisation in ``numpy_baseline_ik.py``;
* one-pose FK vs the 10 µs target (and ur-analytic-ik's FK);
* ``sample_workspace(1_000_000)`` vs the 0.5 s target.

Figures are medians over repeats, all from the same run.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import ur_analytic_ik  # noqa: E402
from _report import machine, table, write_section  # noqa: E402
from numpy_baseline_ik import ik_numpy  # noqa: E402

from ur10core import Arm, flange_to_controller, from_controller  # noqa: E402


def per_call_us(function, arguments, repeats: int = 7) -> float:
    """Median over ``repeats`` of the mean time per call over all ``arguments`` (µs)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for argument in arguments:
            function(argument)
        times.append((time.perf_counter() - start) / len(arguments) * 1e6)
    return statistics.median(times)


def seconds(function, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    arm = Arm.preset("ur10")  # UR's numbers, so ur-analytic-ik solves the very same arm
    rng = np.random.default_rng(0)
    q = -rng.uniform(-np.pi, np.pi, (2000, 6))
    poses = list(arm.fk(q))
    controller_poses = [np.ascontiguousarray(flange_to_controller(T)) for T in poses]

    # sanity: both solvers agree on these poses before they are timed
    for T, Tc in zip(poses[:200], controller_poses[:200]):
        ours = arm.ik(T)
        theirs = from_controller(np.array(ur_analytic_ik.ur10.inverse_kinematics(Tc)).reshape(-1, 6))
        assert len(theirs) == ours.valid.sum()

    ik_ours = per_call_us(arm.ik, poses)
    ik_ours_q = per_call_us(lambda T: arm.ik(T).q, poses)
    ik_theirs = per_call_us(ur_analytic_ik.ur10.inverse_kinematics, controller_poses)
    fk_ours = per_call_us(arm.fk, list(q))
    fk_theirs = per_call_us(lambda x: ur_analytic_ik.ur10.forward_kinematics(*x), list(q.tolist()))

    n = 1_000_000
    Q = -rng.uniform(-np.pi, np.pi, (n, 6))
    T_batch = arm.fk(Q)
    batch_ours = seconds(lambda: arm.ik(T_batch), repeats=5)
    baseline = ik_numpy(arm, T_batch[:200_000])
    ok = ~np.isnan(baseline).any(-1)
    error = np.abs(arm.fk(np.where(ok[..., None], baseline, 0)) - T_batch[:200_000, None]).max((-2, -1))[ok]
    assert error.max() < 1e-8, "the numpy baseline must be correct to be a fair reference"
    batch_numpy = seconds(lambda: ik_numpy(arm, T_batch), repeats=3)
    workspace = seconds(lambda: arm.sample_workspace(1_000_000), repeats=5)

    rows = [
        ["`arm.ik(T)`, one pose, 8 slots", f"{ik_ours:.1f} µs", f"ur-analytic-ik `ur10.inverse_kinematics`: {ik_theirs:.1f} µs",
         "PASS" if ik_ours <= ik_theirs else "FAIL"],
        ["`arm.ik(T).q`, the same and reading the angles", f"{ik_ours_q:.1f} µs", f"{ik_theirs:.1f} µs",
         "PASS" if ik_ours_q <= ik_theirs else "FAIL"],
        ["`arm.ik(T)`, 1 M poses, 8 slots", f"{n / batch_ours / 1e6:.2f} M poses/s",
         f"plain numpy of the course's steps: {n / batch_numpy / 1e6:.2f} M poses/s; target ≥ 1 M/s and ≥ 2×",
         "PASS" if n / batch_ours >= 1e6 and batch_numpy / batch_ours >= 2 else "FAIL"],
        ["`arm.fk(q)`, one pose", f"{fk_ours:.2f} µs", f"target ≤ 10 µs; ur-analytic-ik FK: {fk_theirs:.1f} µs",
         "PASS" if fk_ours <= 10 else "FAIL"],
        ["`arm.sample_workspace(1_000_000)` with manipulability", f"{workspace:.3f} s", "target < 0.5 s",
         "PASS" if workspace < 0.5 else "FAIL"],
    ]
    body = "\n".join(
        [
            "## Kinematics core (`benchmarks/bench_core.py`)",
            "",
            f"Run: {machine()}. Medians of repeated runs; UR10 numbers (`Arm.preset(\"ur10\")`) so",
            "that ur-analytic-ik solves the same arm. Batch speed-up over numpy: "
            f"{batch_numpy / batch_ours:.1f}×; the numpy baseline's worst FK(IK) error "
            f"{error.max():.1e} m (ours: see tests, < 1e-9).",
            "",
            table(["what", "ours", "reference", "verdict"], rows),
        ]
    )
    write_section("core", body)
    print(body)


if __name__ == "__main__":
    main()
