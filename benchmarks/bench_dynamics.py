"""The Jacobian's uses and the UR10's dynamics: how long each takes (docs/kinematics.md §8).

    python benchmarks/bench_dynamics.py

One pose per call (what the app asks for on a drag or an animation frame) and a batch of
10 000 poses per call, numpy only. The forward-dynamics step is one call of
``forward_dynamics`` (one Newton–Euler pass over seven problems and a 6 × 6 solve); a
second of the released arm is 100 Runge–Kutta steps of four such calls. Medians of repeats
from one run.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _report import machine, table, write_section  # noqa: E402

from ur10core import Arm, dynamics  # noqa: E402

BATCH = 10_000


def per_call_us(call, repeats: int = 5, calls: int = 200) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            call()
        times.append((time.perf_counter() - start) / calls * 1e6)
    return statistics.median(times)


def per_pose_us(call, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append((time.perf_counter() - start) / BATCH * 1e6)
    return statistics.median(times)


def main() -> None:
    arm = Arm.preset("ur10")
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-np.pi, np.pi, (BATCH, 6)), rng.normal(size=(BATCH, 6))
    one, rates = q[0], qd[0]
    force, twist = np.array([0.0, 0.0, -50.0]), np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.1])
    rows = []
    for label, single, batch in (
        ("tool twist J q̇", lambda: arm.tool_twist(one, rates), lambda: arm.tool_twist(q, qd)),
        ("joint rates (damped inverse)", lambda: arm.joint_rates(one, twist), lambda: arm.joint_rates(q, twist)),
        ("static torques Jᵀ F", lambda: arm.static_torques(one, force), lambda: arm.static_torques(q, force)),
        ("ellipsoids (both)", lambda: arm.ellipsoids(one), lambda: arm.ellipsoids(q)),
        ("gravity torques", lambda: arm.gravity_torques(one), lambda: arm.gravity_torques(q)),
        ("inverse dynamics (Newton–Euler)", lambda: dynamics.inverse_dynamics(arm, one, rates, rates),
         lambda: dynamics.inverse_dynamics(arm, q, qd, qd)),
        ("forward dynamics step", lambda: dynamics.forward_dynamics(arm, one, rates, np.zeros(6)),
         lambda: dynamics.forward_dynamics(arm, q, qd, np.zeros(6))),
    ):
        rows.append([label, f"{per_call_us(single):.0f} µs", f"{per_pose_us(batch):.2f} µs"])
    start = time.perf_counter()
    dynamics.release(arm, np.radians([0, -60, 0, -90, 0, 0]), duration=1.0, dt=0.01)
    released = time.perf_counter() - start
    body = "\n".join([
        "## The Jacobian's uses and the UR10's dynamics (`benchmarks/bench_dynamics.py`)",
        "",
        f"Run: {machine()}. numpy only. One pose per call, and a batch of {BATCH:,} poses in one call (per pose); "
        "medians of repeats.",
        "",
        table(["computation", "one pose", "batch, per pose"], rows),
        "",
        f"One second of the released arm (100 Runge–Kutta steps of 10 ms, four forward-dynamics calls each): "
        f"{released:.2f} s to compute.",
    ])
    write_section("dynamics", body)
    print(body)


if __name__ == "__main__":
    main()
