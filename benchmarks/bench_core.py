"""Speed of the kinematics core on both backends, beside its references, written to BENCHMARKS.md.

    python benchmarks/bench_core.py

Each backend is measured in its own process (``UR10CORE_BACKEND=compiled`` and
``=numpy``; the backend is chosen when ur10core is imported), the references in this
one, all in the same run (ur-analytic-ik's IK, pinocchio and the numpy baseline in each
backend's, in turns with its own calls: the ratios are taken there):

* one-pose IK (all 8 slots), without and with a hint, vs ur-analytic-ik's UR10
  ``inverse_kinematics`` (C++, timed in turns with them in each backend's process; target
  ≤ 0.3× its time), and with a huge hint vs an ordinary one;
* batch IK of 200 000 poses vs the plain numpy vectorisation in ``numpy_baseline_ik.py``, and
  as a share of what the hardware could do (:data:`HARDWARE_POSES_PER_CORE`);
* one-pose FK vs the 10 µs target (and ur-analytic-ik's FK), and FK and the Jacobian vs
  pinocchio's on the same DH table (when pinocchio is installed: ``pip install pin``; a
  benchmark reference only, not a test dependency);
* ``sample_workspace(1_000_000)`` vs the 0.5 s target.

Figures are medians over repeats.

    python benchmarks/bench_core.py --against REF [--rounds N] [--section NAME]

times the UR10's one-pose IK, batch IK, FK and the app's drag step (``ArmState.move_target``)
on this checkout and on git revision ``REF`` (a worktree, the compiled kernel copied in or,
if its C differs, built there), alternately in their own processes, ``N`` rounds (3), and
writes the section ``NAME`` ("before_after"): what a change of the core cost the UR10.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
# the checkout measured (--against runs this script on an older one too)
sys.path.insert(0, os.environ.get("UR10_BENCH_CHECKOUT", str(Path(__file__).resolve().parent.parent)))

from _report import machine, table, write_section  # noqa: E402

BATCH = 200_000
#: An 8-branch solve is about 1.2 kFLOP (some 200 arithmetic operations and 20 atan2); at about
#: 22 GFLOP/s of double precision per core (AVX-512) that is about 15 M poses/s per core.
HARDWARE_POSES_PER_CORE = 15e6
#: Issue 32: one-pose IK of all eight branches in at most this share of ur-analytic-ik's time.
ONE_POSE_RATIO = 0.3


def per_call_us(function, arguments, repeats: int = 7) -> float:
    """Median over ``repeats`` of the mean time per call over all ``arguments`` (µs)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for argument in arguments:
            function(*argument)
        times.append((time.perf_counter() - start) / len(arguments) * 1e6)
    return statistics.median(times)


def side_by_side(calls: dict, repeats: int = 7) -> dict:
    """:func:`per_call_us` of each ``name: (function, arguments)``, their repeats taken in turn.

    Taking turns puts this shared machine's drift on every call alike: a ratio of two of
    them is then one measurement, not two taken minutes apart.
    """
    times = {name: [] for name in calls}
    for _ in range(repeats):
        for name, (function, arguments) in calls.items():
            times[name].append(per_call_us(function, arguments, repeats=1))
    return {name: statistics.median(values) for name, values in times.items()}


def seconds(function, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _workload():
    from ur10core import Arm

    arm = Arm.preset("ur10")  # UR's numbers, so ur-analytic-ik solves the very same arm
    rng = np.random.default_rng(0)
    q = -rng.uniform(-np.pi, np.pi, (2000, 6))
    T_batch = arm.fk(-rng.uniform(-np.pi, np.pi, (BATCH, 6)))
    return arm, q, arm.fk(q), T_batch


def measure() -> dict:
    """This process's backend on the common workload."""
    import ur_analytic_ik
    from numpy_baseline_ik import ik_numpy

    import ur10core
    from ur10core import flange_to_controller

    arm, q, poses, T_batch = _workload()
    controller_poses = [np.ascontiguousarray(flange_to_controller(T)) for T in poses]
    one_pose = side_by_side({
        "ik_one_us": (arm.ik, [(T,) for T in poses]),
        "ik_one_hint_us": (lambda T, h: arm.ik(T, hint=h), list(zip(poses, q))),
        "ur_analytic_ik_us": (ur_analytic_ik.ur10.inverse_kinematics, [(T,) for T in controller_poses]),
    })
    return {
        "backend": ur10core.BACKEND,
        **one_pose,
        # the old C wrap() subtracted 2π in a loop: 0.26 s at 1e9, forever from 1e16
        "ik_huge_hint_us": per_call_us(lambda T, h: arm.ik(T, hint=h),
                                       [(poses[k], np.append(q[k, :5], h)) for k in range(300) for h in (1e9, 1e16, 1e300)]),
        **{key: BATCH / (us * 1e-6) for key, us in side_by_side({
            "batch_per_s": (arm.ik, [(T_batch,)]),
            "numpy_baseline_per_s": (ik_numpy, [(arm, T_batch)]),
        }, repeats=3).items()},
        "pinocchio_fk_us": float("nan"), "pinocchio_jacobian_us": float("nan"),
        **side_by_side({
            "fk_one_us": (arm.fk, [(x,) for x in q]),
            "jacobian_one_us": (arm.jacobian, [(x,) for x in q]),
            **pinocchio_calls(arm, q),
        }),
        "workspace_s": seconds(lambda: arm.sample_workspace(1_000_000), repeats=5),
    }


def pinocchio_model(arm):
    """pinocchio's model of ``arm``'s modified DH table: joint i about z after RotX(α) TransX(a) TransZ(d)."""
    import pinocchio as pin

    model = pin.Model()
    parent = 0
    for k, row in enumerate(arm.dh.rows):
        c, s = np.cos(row.alpha), np.sin(row.alpha)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        placement = pin.SE3(rotation, np.array([row.a, -s * row.d, c * row.d]))
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{k + 1}")
    return model


def pinocchio_calls(arm, q: np.ndarray) -> dict:
    """pinocchio's one-pose FK (T06) and flange Jacobian in the base frame, checked against ours
    first, as :func:`side_by_side` takes them; none where pinocchio is not installed."""
    try:
        import pinocchio as pin
    except ImportError:
        return {}

    model = pinocchio_model(arm)
    data = model.createData()
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def fk(x):
        pin.forwardKinematics(model, data, x)
        return data.oMi[6].homogeneous

    def jacobian(x):
        pin.computeJointJacobians(model, data, x)
        return pin.getJointJacobian(model, data, 6, world)

    for x in q[:200]:
        assert np.abs(fk(x) - arm.fk(x)).max() < 1e-12 and np.abs(jacobian(x) - arm.jacobian(x)).max() < 1e-12
    return {"pinocchio_fk_us": (fk, [(x,) for x in q]), "pinocchio_jacobian_us": (jacobian, [(x,) for x in q])}


def references() -> dict:
    import ur_analytic_ik
    from numpy_baseline_ik import ik_numpy

    from ur10core import flange_to_controller, from_controller

    arm, q, poses, T_batch = _workload()
    controller_poses = [np.ascontiguousarray(flange_to_controller(T)) for T in poses]
    # sanity: both solvers agree on these poses before they are timed
    for T, Tc in zip(poses[:200], controller_poses[:200]):
        theirs = from_controller(np.array(ur_analytic_ik.ur10.inverse_kinematics(Tc)).reshape(-1, 6))
        assert len(theirs) == arm.ik(T).valid.sum()
    baseline = ik_numpy(arm, T_batch[:200_000])
    ok = ~np.isnan(baseline).any(-1)
    error = np.abs(arm.fk(np.where(ok[..., None], baseline, 0)) - T_batch[:200_000, None]).max((-2, -1))[ok]
    assert error.max() < 1e-8, "the numpy baseline must be correct to be a fair reference"
    # and where it is not: exactly wrist-singular poses (θ5 = 0 or π), which ur10core solves every one of
    singular = q.copy()
    singular[:, 4] = np.where(np.arange(len(q)) % 2 == 0, 0.0, np.pi)
    T_singular = arm.fk(singular)
    found = ~np.isnan(ik_numpy(arm, T_singular)).any(-1)
    correct = found & (np.abs(arm.fk(np.nan_to_num(ik_numpy(arm, T_singular))) - T_singular[:, None]).max((-2, -1)) < 1e-9)
    assert arm.ik(T_singular).reachable.all()
    return {
        "numpy_baseline_singular_solved": float(correct.any(-1).mean()),
        "ur_analytic_fk_us": per_call_us(ur_analytic_ik.ur10.forward_kinematics, [tuple(x) for x in q.tolist()]),
        "numpy_baseline_error": float(error.max()),
    }


def measure_speed() -> dict:
    """The UR10's hot paths on the compiled backend, for :func:`before_after` (this process's checkout)."""
    import importlib

    import ur10core

    # the checkout is not installed: its app package goes by its folder's name (in this process only)
    ArmState = importlib.import_module("app.state").ArmState
    arm, q, poses, T_batch = _workload()
    state = ArmState(arm, q[0])
    step = np.eye(4)
    step[:3, 3] = (0.0005, 0.0, 0.0)
    start = state.last.flange.copy()
    drags = [start @ np.linalg.matrix_power(step, k % 200) for k in range(400)]  # there and back, half a mm a step

    def drawn(snapshot):  # and what the UR10's mesh drawing reads of it on every drag (worked out lazily since 29)
        return snapshot.link_wxyz, snapshot.ghost_wxyz, snapshot.ghost_frames
    assert Path(ur10core.__file__).resolve().is_relative_to(Path(os.environ.get("UR10_BENCH_CHECKOUT", "/")).resolve())
    return {
        "backend": ur10core.BACKEND,
        "ik_one_hint_us": per_call_us(lambda T, h: arm.ik(T, hint=h), list(zip(poses, q))),
        "batch_per_s": BATCH / seconds(lambda: arm.ik(T_batch), repeats=3),
        "fk_one_us": per_call_us(arm.fk, [(x,) for x in q]),
        "drag_step_us": per_call_us(lambda T: drawn(state.move_target(T)), [(T,) for T in drags]),
    }


def before_after(ref: str, rounds: int = 3, section: str = "before_after") -> None:
    import shutil
    import tempfile

    root = Path(__file__).resolve().parent.parent
    tree = Path(tempfile.mkdtemp()) / "before"
    subprocess.run(["git", "-C", str(root), "worktree", "add", "--detach", str(tree), ref], check=True, capture_output=True)
    try:
        if (tree / "ur10core" / "_kernels.c").read_bytes() == (root / "ur10core" / "_kernels.c").read_bytes():
            for built in (root / "ur10core").glob("_kernels*.so"):  # the same C source: the same kernel
                shutil.copy(built, tree / "ur10core")
        else:  # the kernel changed too: build the old one in its checkout
            subprocess.run([sys.executable, "setup.py", "-q", "build_ext", "--inplace"], cwd=tree, check=True, capture_output=True)

        def run(checkout: Path) -> dict:
            env = dict(os.environ, UR10CORE_BACKEND="compiled", UR10_BENCH_CHECKOUT=str(checkout))
            done = subprocess.run([sys.executable, __file__, "--measure-speed"], env=env, cwd=checkout,
                                  capture_output=True, text=True, check=True)
            return json.loads(done.stdout.strip().splitlines()[-1])

        runs = {"before": [], "after": []}
        for _ in range(rounds):  # alternately, so that the machine's drift falls on both
            runs["before"].append(run(tree))
            runs["after"].append(run(root))
    finally:
        subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(tree)], check=False)
    median = {side: {key: statistics.median(r[key] for r in rs) for key in rs[0] if key != "backend"} for side, rs in runs.items()}
    b, a = median["before"], median["after"]
    commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    rows = [
        ["`arm.ik(T, hint=q)`, one pose (the drag handler's call)", f"{b['ik_one_hint_us']:.2f} µs", f"{a['ik_one_hint_us']:.2f} µs",
         f"{a['ik_one_hint_us'] / b['ik_one_hint_us']:.2f}"],
        [f"`arm.ik(T)`, {BATCH:,} poses", f"{b['batch_per_s'] / 1e6:.2f} M poses/s", f"{a['batch_per_s'] / 1e6:.2f} M poses/s",
         f"{b['batch_per_s'] / a['batch_per_s']:.2f}"],
        ["`arm.fk(q)`, one pose", f"{b['fk_one_us']:.2f} µs", f"{a['fk_one_us']:.2f} µs", f"{a['fk_one_us'] / b['fk_one_us']:.2f}"],
        ["drag step: `ArmState.move_target(T)` and what the mesh drawing reads of it (IK with hint, nearest branch, frames, ghost poses)", f"{b['drag_step_us']:.1f} µs",
         f"{a['drag_step_us']:.1f} µs", f"{a['drag_step_us'] / b['drag_step_us']:.2f}"],
    ]
    body = "\n".join([
        "## The UR10's speed before and after a change of the core (`benchmarks/bench_core.py --against REF`)",
        "",
        f"Run: {machine()}. Before: `{ref}`; after: `{commit}` (and the working tree). The compiled backend; each",
        f"checkout in its own process, alternately, {rounds} rounds; medians of the rounds' medians. Time ratio",
        "after/before (below 1: faster).",
        "",
        table(["what", "before", "after", "after / before (time)"], rows),
    ])
    write_section(section, body)
    print(body)


def on_backend(backend: str) -> dict:
    env = dict(os.environ, UR10CORE_BACKEND=backend)
    done = subprocess.run([sys.executable, __file__, "--measure"], env=env, capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["backend"] == backend
    return result


def main() -> None:
    compiled, numpy_backend = on_backend("compiled"), on_backend("numpy")
    ref = references()
    c, n = compiled, numpy_backend

    def pass_if(ok: bool) -> str:
        return "PASS" if ok else "FAIL"

    has_pinocchio = not np.isnan(c["pinocchio_fk_us"])  # timed in turns with the compiled backend's calls

    def against_pinocchio(what: str, us: float, ratio: float) -> str:
        if not has_pinocchio:
            return f"pinocchio not installed (`pip install pin`); target (compiled) ≤ {ratio:g}× its time"
        return f"pinocchio {what}: {us:.2f} µs; target (compiled) ≤ {ratio:g}×"

    theirs = c["ur_analytic_ik_us"]  # timed in turns with the compiled backend's calls, in its process
    rows = [
        ["`arm.ik(T)`, one pose, 8 slots", f"{c['ik_one_us']:.1f} µs ({c['ik_one_us'] / theirs:.2f}×)",
         f"{n['ik_one_us']:.1f} µs",
         f"ur-analytic-ik `ur10.inverse_kinematics`: {theirs:.1f} µs; target (compiled) ≤ {ONE_POSE_RATIO}×",
         f"compiled {pass_if(c['ik_one_us'] <= ONE_POSE_RATIO * theirs)}"],
        ["`arm.ik(T, hint=q)`, one pose, 8 slots (the drag handler's call)",
         f"{c['ik_one_hint_us']:.1f} µs ({c['ik_one_hint_us'] / theirs:.2f}×)",
         f"{n['ik_one_hint_us']:.1f} µs", f"{theirs:.1f} µs; target (compiled) ≤ {ONE_POSE_RATIO}×",
         f"compiled {pass_if(c['ik_one_hint_us'] <= ONE_POSE_RATIO * theirs)}"],
        ["`arm.ik(T, hint=q)`, one pose, θ6's hint 1e9, 1e16 or 1e300 rad", f"{c['ik_huge_hint_us']:.1f} µs",
         f"{n['ik_huge_hint_us']:.1f} µs", "within 2× of an ordinary hint (the row above)",
         pass_if(c["ik_huge_hint_us"] <= 2 * c["ik_one_hint_us"] and n["ik_huge_hint_us"] <= 2 * n["ik_one_hint_us"])],
        [f"`arm.ik(T)`, {BATCH:,} poses, 8 slots (both cores)", f"{c['batch_per_s'] / 1e6:.2f} M poses/s "
         f"({c['batch_per_s'] / c['numpy_baseline_per_s']:.1f}× the baseline; "
         f"{100 * c['batch_per_s'] / (os.cpu_count() * HARDWARE_POSES_PER_CORE):.0f} % of ~{HARDWARE_POSES_PER_CORE / 1e6:.0f} M/s a core)",
         f"{n['batch_per_s'] / 1e6:.2f} M poses/s",
         f"plain numpy of the course's steps (no singular cases): {c['numpy_baseline_per_s'] / 1e6:.2f} M poses/s; "
         "target (compiled) ≥ 5×",
         f"compiled {pass_if(c['batch_per_s'] >= 5 * c['numpy_baseline_per_s'])}"],
        ["`arm.fk(q)`, one pose", f"{c['fk_one_us']:.2f} µs", f"{n['fk_one_us']:.2f} µs",
         f"target ≤ 10 µs; ur-analytic-ik FK: {ref['ur_analytic_fk_us']:.1f} µs",
         pass_if(max(c["fk_one_us"], n["fk_one_us"]) <= 10)],
        ["`arm.fk(q)`, one pose, against pinocchio on the same DH table", f"{c['fk_one_us']:.2f} µs", f"{n['fk_one_us']:.2f} µs",
         against_pinocchio("`forwardKinematics` and T06", c["pinocchio_fk_us"], 1.5),
         f"compiled {pass_if(c['fk_one_us'] <= 1.5 * c['pinocchio_fk_us'])}" if has_pinocchio else "n/a"],
        ["`arm.jacobian(q)`, one pose, flange, base frame", f"{c['jacobian_one_us']:.2f} µs", f"{n['jacobian_one_us']:.2f} µs",
         against_pinocchio("`computeJointJacobians` and `getJointJacobian` (same answer to 1e-12)",
                           c["pinocchio_jacobian_us"], 2),
         f"compiled {pass_if(c['jacobian_one_us'] <= 2 * c['pinocchio_jacobian_us'])}" if has_pinocchio else "n/a"],
        ["`arm.sample_workspace(1_000_000)` with manipulability", f"{c['workspace_s']:.3f} s", f"{n['workspace_s']:.3f} s",
         "target < 0.5 s", pass_if(max(c["workspace_s"], n["workspace_s"]) < 0.5)],
    ]
    body = "\n".join(
        [
            "## Kinematics core (`benchmarks/bench_core.py`)",
            "",
            f"Run: {machine()}. Medians of repeated runs, each backend in its own process, the",
            "other references in a third, one after the other; ur-analytic-ik's IK, pinocchio and the numpy baseline",
            "are timed in each backend's process, in turns with its own IK calls (the ratios are taken",
            "there: on this shared machine, runs minutes apart differ by up to 2×). UR10 numbers (`Arm.preset(\"ur10\")`) so that",
            "ur-analytic-ik solves the same arm. The compiled kernel earns its place on the one-pose",
            f"and batch IK rows: {n['ik_one_us'] / c['ik_one_us']:.0f}× and {c['batch_per_s'] / n['batch_per_s']:.1f}× the numpy backend.",
            "The plain numpy baseline runs the course's steps with no singular cases: on regular poses",
            f"its worst FK(IK) error is {ref['numpy_baseline_error']:.1e} m, but it solves only "
            f"{100 * ref['numpy_baseline_singular_solved']:.0f} % of 2000 exactly wrist-singular",
            "poses (θ5 = 0 or π), all of which both backends solve.",
            "",
            table(["what", "compiled backend", "numpy backend", "reference", "verdict"], rows),
        ]
    )
    write_section("core", body)
    print(body)


if __name__ == "__main__":
    if sys.argv[1:] == ["--measure"]:
        print(json.dumps(measure()))
    elif sys.argv[1:] == ["--measure-speed"]:
        print(json.dumps(measure_speed()))
    elif sys.argv[1:2] == ["--against"]:
        import argparse

        parser = argparse.ArgumentParser(prog="bench_core.py")
        parser.add_argument("--against", required=True)
        parser.add_argument("--rounds", type=int, default=3)
        parser.add_argument("--section", default="before_after")
        arguments = parser.parse_args()
        before_after(arguments.against, arguments.rounds, arguments.section)
    else:
        main()
