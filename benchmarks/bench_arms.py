"""IK speed of the course's other arms, and the numerical IK beside the KR210's closed form.

    python benchmarks/bench_arms.py

For each preset with a closed form: one-pose IK (every slot, no hint), batch IK of
100 000 poses, per pose, on the backend this run has and, for the spherical-wrist arms,
on their numpy code too, beside the UR10's in the same run; and the app's work on one drag
event. For the KR210 also the numerical solver (damped least squares from ``STARTS`` starts,
:mod:`ur10core.solvers.numerical`): its time for one pose and how often it finds every
branch the closed form lists. Figures are medians over repeats, from one run.
"""

from __future__ import annotations

import asyncio
import gc
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _report import machine, steady_cpu, table, write_section  # noqa: E402

from ur10core import BACKEND, Arm  # noqa: E402
from ur10core.serial import PRESETS  # noqa: E402
from ur10core.solvers.numerical import STARTS  # noqa: E402

BATCH = 100_000
NUMERICAL_POSES = 200
DRAG_STEPS = 2000
#: The app's target for the server's work on one drag event (the UR10's, BENCHMARKS.md *drag*).
DRAG_TARGET_MS = 5.0


def joints(arm: Arm, n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(arm.limits[:, 0], arm.limits[:, 1], (n, arm.n_joints))


def one_pose_us(arm: Arm, poses: np.ndarray, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for T in poses:
            arm.ik(T)
        times.append((time.perf_counter() - start) / len(poses) * 1e6)
    return statistics.median(times)


def batch_us(arm: Arm, poses: np.ndarray, repeats: int = 3) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        arm.ik(poses)
        times.append((time.perf_counter() - start) / len(poses) * 1e6)
    return statistics.median(times)


def on_numpy(arm: Arm) -> Arm:
    """The same arm solved by its solver's numpy code (what the numpy backend runs)."""
    plain = Arm.preset(arm.name)
    plain._own_ik = None
    return plain


def drag_ms(arm: Arm, server) -> tuple[float, float, float]:
    """One drag event's work in the app, before viser sends it: IK of the new target with the
    current joints as hint, the nearest valid branch, its frames, and drawing the arm, its
    ghosts and DH frames, on viser's event loop and batched as the app does. p50 and p99 (ms)
    in the default view, and p99 with the singularity overlay on too."""
    from ur10teach.features.course_arms.scene import CourseArmScene
    from ur10teach.features.drawings import reach
    from ur10teach.state import ArmState

    state = ArmState(arm)
    scene = CourseArmScene(server.scene, arm, state.last, reach(arm))
    rng = np.random.default_rng(4)
    q = state.last.q + np.cumsum(rng.normal(0.0, 0.01, (DRAG_STEPS, arm.n_joints)), axis=0)  # a student's hand
    q = np.clip(q, arm.limits[:, 0], arm.limits[:, 1])
    loop = server.get_event_loop()

    async def step(T: np.ndarray) -> float:
        """One drag event where the app serves it: on viser's event loop (``ur10teach.serving.workers.DragQueue``), one batch."""
        start = time.perf_counter()
        with server.atomic():
            scene.render(state.move_target(T))
        server.flush()
        return (time.perf_counter() - start) * 1e3

    results = []
    for overlay in (False, True):
        if scene.overlay is not None:
            scene.overlay.enabled = overlay
        times = []
        for T in arm.fk(q if not overlay else q[::-1]):
            times.append(asyncio.run_coroutine_threadsafe(step(T), loop).result())
        results.append(times)
    return float(np.percentile(results[0], 50)), float(np.percentile(results[0], 99)), float(np.percentile(results[1], 99))


def numerical_rate(arm: Arm) -> tuple[float, float, float, float]:
    """Per pose: ms of the numerical IK (one call each), share of poses with every branch found,
    share of branches found, and how many reported solutions the closed form does not list."""
    numerical = Arm(arm.dh, arm.limits, None, "kr210 (numerical)")
    q = joints(arm, NUMERICAL_POSES, 9)
    T = arm.fk(q)
    analytic = arm.ik(T)
    start = time.perf_counter()
    found = [numerical.ik(pose) for pose in T]
    per_pose_ms = (time.perf_counter() - start) / len(T) * 1e3
    complete = hits_total = branches = strays = 0
    for k, solution in enumerate(found):
        ours = solution.q[solution.valid]
        listed = analytic.q[k][analytic.valid[k]]
        hits = [len(ours) and np.abs(np.where(arm.revolute, (ours - b + np.pi) % (2 * np.pi) - np.pi, ours - b)).max(-1).min() < 1e-6
                for b in listed]
        complete += all(hits)
        hits_total += sum(hits)
        branches += len(listed)
        strays += len(ours) - sum(hits)
    return per_pose_ms, complete / len(T), hits_total / branches, strays


def main() -> None:
    import viser

    server = viser.ViserServer(port=0, verbose=False)  # no browser: what is timed is the server's own work
    gc.collect()
    gc.freeze()  # as app.server does once it has loaded
    ur10 = Arm.preset("ur10")
    ur10_poses = ur10.fk(joints(ur10, BATCH, 1))
    ur10_one, ur10_batch = one_pose_us(ur10, ur10_poses[:2000]), batch_us(ur10, ur10_poses)
    rows = [["`ur10`, for comparison (8 slots)", f"{ur10_one:.1f} µs", f"{ur10_batch:.2f} µs", "BENCHMARKS.md *drag*", "—",
             "every branch, by construction"]]
    for name in PRESETS:
        arm = Arm.preset(name)
        poses = arm.fk(joints(arm, BATCH, 1))
        one = one_pose_us(arm, poses[:2000])
        batch = batch_us(arm, poses)
        one_cell, batch_cell = f"{one:.1f} µs", f"{batch:.2f} µs"
        if arm._own_ik is not None:  # the compiled kernel solves it: against the UR10's, and the numpy code beside
            plain = on_numpy(arm)
            one_cell += f" ({one / ur10_one:.1f} × the UR10's; numpy {one_pose_us(plain, poses[:2000]):.0f} µs)"
            batch_cell += f" ({batch / ur10_batch:.1f} × the UR10's; numpy {batch_us(plain, poses):.2f} µs)"
        floor = steady_cpu(max_wait=120.0)[:2]  # the tails are the machine's too: measured just before
        p50, p99, p99_overlay = drag_ms(arm, server)
        rows.append([f"`{name}`, closed form ({len(arm.slot_labels)} slots)", one_cell, batch_cell,
                     f"{p50:.2f} / {p99:.2f} ms; overlay on: p99 {p99_overlay:.2f} ms",
                     "{:.2f} / {:.2f} ms".format(*floor), "every branch, by construction"])
    server.stop()
    kr210 = Arm.preset("kr210")
    ms, complete, share, strays = numerical_rate(kr210)
    rows.append([f"`kr210`, numerical IK ({STARTS} starts, damped least squares)", f"{ms * 1e3:.0f} µs", "—", "—", "—",
                 f"all of the closed form's branches on {100 * complete:.1f} % of {NUMERICAL_POSES} random poses; "
                 f"{100 * share:.1f} % of its branches; {strays} solutions it does not list"])
    body = "\n".join([
        "## The course's other arms (`benchmarks/bench_arms.py`)",
        "",
        f"Run: {machine()}, {BACKEND} backend: the KR210, elbow and Stanford arms on the compiled kernel's `wrist_ik` "
        "(their numpy code in brackets), the smaller arms on numpy. One-pose IK: every slot of one pose "
        f"per call, no hint, over 2 000 random poses within the joint limits; batch: {BATCH:,} such poses in one call. "
        "Target (issue 32): the spherical-wrist arms within 3 × the UR10's time per pose, one pose and batch. "
        "Medians of repeats. Drag step: the server's work on one drag event (IK with the current joints as hint, "
        "the nearest branch, drawing the arm, its ghosts and DH frames into viser's queue, on viser's event loop "
        "as the app's drag queue runs it), p50 / p99 over "
        f"{DRAG_STEPS:,} steps of a random walk, then p99 with the singularity overlay on too, against the "
        f"{DRAG_TARGET_MS:g} ms the UR10's drag is held to. Machine floor: a fixed unit of work timed just before "
        "each arm's drag, once its p99 was within 1.5 × its p50 or two minutes had passed (`_report.work_unit_floor`): "
        "on this shared virtual machine every tail sits on it. The numerical row solves one pose per call and compares "
        "its solutions with the closed form's.",
        "",
        table(["arm, solver", "one-pose IK", "batch IK, per pose", f"drag step p50 / p99 (target {DRAG_TARGET_MS:g} ms)",
               "machine floor p50 / p99", "branches found"], rows),
    ])
    write_section("arms", body)
    print(body)


if __name__ == "__main__":
    main()
