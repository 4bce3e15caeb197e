"""The compiled kernel and the numpy backend give the same results, corners included.

``ur10core._numpy_kernels`` and ``ur10core._kernels`` are called side by side here,
whichever backend the rest of the suite runs on, so ``scripts/test.sh`` runs this module
once, not again in its run on ``UR10CORE_BACKEND=numpy``. The plain-Python reference
(``ik_reference``) is the numpy backend's one-pose path, so it is compared too.
"""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ur10core import Arm, _numpy_kernels, ik_reference
from ur10core._backend import configured

from ur10dev.waiting import HANG_TIMEOUT

from .conftest import random_joints

pytestmark = pytest.mark.core

try:
    from ur10core import _kernels
except ImportError:
    if os.environ.get("UR10_REQUIRE_COMPILED"):  # CI has a compiler: a kernel that did not build is a failure
        raise
    pytest.skip("the compiled kernel was not built (no C compiler)", allow_module_level=True)
compiled = configured(_kernels)
ROOT = Path(__file__).resolve().parent.parent
FIELDS = ("q", "valid", "wrist_singular", "elbow_singular", "shoulder_singular", "failure", "rho", "elbow_distance")


def _batch(module, arm: Arm, T: np.ndarray, hints: np.ndarray) -> dict:
    """``module.ik_batch`` on poses (n, 4, 4) with hints (n, 3): θ6, the shoulder's reach A, θ3 (NaN: none)."""
    n = len(T)
    out = (np.empty((n, 8, 6)), np.empty((n, 8), bool), np.empty((n, 8), bool), np.empty((n, 8), bool),
           np.empty(n, bool), np.empty((n, 8), np.int8), np.empty(n), np.empty((n, 8)))
    columns = (np.ascontiguousarray(hints[:, k], dtype=float) for k in range(3))
    bad = module.ik_batch(np.ascontiguousarray(T.reshape(n, 16)), *columns, arm.dh_lengths, *out)
    assert bad == -1
    return dict(zip(FIELDS, out))


def _one(module, arm: Arm, T: np.ndarray, hints: np.ndarray) -> dict:
    return dict(zip(FIELDS, module.ik_one(np.ascontiguousarray(T), *map(float, hints), arm.dh_lengths)))


def _hints(arm: Arm, q: np.ndarray) -> np.ndarray:
    """What Arm.ik hands the kernels for the joints ``q`` (n, 6)."""
    return np.stack([q[:, 5], arm.singularity_factors(q)[:, 0], q[:, 2]], axis=-1)


#: At the stretched or folded elbow θ3 = ±acos(c3) is fixed only to √(rounding): one bit of
#: difference in r between two implementations moves it by 1.5e-8 rad (docs/kinematics.md §4.3).
ELBOW_SINGULAR_ANGLES = 1e-7


def _assert_same(a: dict, b: dict, where: str, angle_tolerance: float = 1e-12) -> None:
    """Flags and failure codes equal; ρ and the distances to 1e-12 m; angles to ``angle_tolerance``, as angles: at
    θ = ±π a last bit of sin θ picks π or −π + 1 ulp, one angle (numpy 1.26's arithmetic picks the other one
    than the kernel's at θ1 = π; numpy 2's, on this CPU, the same)."""
    for name in ("valid", "wrist_singular", "elbow_singular", "shoulder_singular", "failure"):
        np.testing.assert_array_equal(a[name], b[name], err_msg=f"{name} differs ({where})")
    for name in ("rho", "elbow_distance"):
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-12, err_msg=f"{name} differs ({where})")
    tolerance = np.where(a["elbow_singular"], ELBOW_SINGULAR_ANGLES, angle_tolerance)[..., None]
    difference = np.where(np.isnan(a["q"]) & np.isnan(b["q"]), 0.0, np.abs(_numpy_kernels.wrap(a["q"] - b["q"])))
    assert (difference <= tolerance).all(), f"angles differ by {np.nanmax(difference):.3g} ({where})"
    valid_q = a["q"][a["valid"]]
    assert ((valid_q > -math.pi) & (valid_q <= math.pi)).all(), f"angles outside (−π, π] ({where})"


def _corner_poses(arm: Arm) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Poses and hints (θ6, A, θ3) at the corners where two implementations could part."""
    rng = np.random.default_rng(40)
    joints, hints, names = [], [], []

    def add(q, name, hint6=0.0, generating_hint=False):
        joints.append(np.asarray(q, float))
        hints.append(_hints(arm, q[None])[0] if generating_hint else (hint6, math.nan, math.nan))
        names.append(name)

    for k in range(60):
        q = random_joints(1, seed=100 + k)[0]
        q_w = q.copy()
        q_w[4] = [0.0, math.pi, -math.pi][k % 3]
        add(q_w, f"wrist exactly singular {k}", hint6=rng.uniform(-4, 4))
        q_e = q.copy()
        q_e[2] = [0.0, math.pi, -math.pi][k % 3]
        add(q_e, f"elbow exactly singular {k}", generating_hint=k % 2 == 0)
        q_s = arm.singular_configuration("shoulder", q)
        add(q_s, f"shoulder exactly singular {k}", generating_hint=k % 2 == 0)
        add(arm.singular_configuration("wrist", arm.singular_configuration("elbow", q_s)), f"all three {k}", hint6=q[5])
        q_pi = q.copy()
        q_pi[k % 6] = math.pi if k % 2 else -math.pi
        add(q_pi, f"a joint at ±π {k}", hint6=math.pi)
    for hint in (1e9, -1e9, 1e16, 1e300, -1e308, 2 * math.pi * 1e6 + 0.3):
        q = np.radians([45, 90, 0, -90, 0, 60])
        add(q, f"hint {hint:g}", hint6=hint)
    poses = arm.fk(np.array(joints))
    hints = np.array(hints)
    # ±1e-7 m around the reach boundary: the stretched arm moved along its own length
    for k in range(30):
        q = random_joints(1, seed=200 + k)[0]
        q[2] = 0.0
        T = arm.fk(q)
        geometry = arm.singularity_geometry(q)
        along = geometry.p4 - geometry.elbow_center  # in the arm plane, from the shoulder to the frame-4 origin
        along /= np.linalg.norm(along)
        for shift in (-1e-7, 1e-7):
            moved = T.copy()
            moved[:3, 3] += shift * along
            poses = np.concatenate([poses, moved[None]])
            hints = np.concatenate([hints, [(q[5], math.nan, math.nan)]])
            names.append(f"{shift:+g} m from the reach boundary {k}")
    return poses, hints, names


@pytest.mark.parametrize("preset", Arm.UR_PRESETS)
def test_backends_agree_at_the_corners(preset):
    arm = Arm.preset(preset)
    T, hints, names = _corner_poses(arm)
    c = _batch(compiled, arm, T, hints)
    n = _batch(_numpy_kernels, arm, T, hints)
    for k, name in enumerate(names):
        c_k = {field: value[k] for field, value in c.items()}
        n_k = {field: value[k] for field, value in n.items()}
        one_c = _one(compiled, arm, T[k], hints[k])
        one_ref = _one(_numpy_kernels, arm, T[k], hints[k])  # the plain-Python reference
        for other, label in ((n_k, "numpy batch"), (one_c, "compiled one pose"), (one_ref, "reference")):
            # at an exact singularity the free angle is the hint's in every implementation
            _assert_same(c_k, other, f"{name}: compiled batch vs {label}", angle_tolerance=1e-9)
    # 1e-7 m beyond the boundary is out of reach for the stretched arm's own slot pair, 1e-7 m inside is not
    outer = arm.a2 + arm.a3
    for k, name in enumerate(names):
        if "reach boundary" in name:
            pair = np.abs(c["elbow_distance"][k] - outer).argmin()
            beyond = name.startswith("+")
            assert c["elbow_distance"][k, pair] - outer == pytest.approx(1e-7 if beyond else -1e-7, abs=1e-9)
            assert c["valid"][k, pair] != beyond and (c["failure"][k, pair] == 2) == beyond


def test_backends_agree_on_random_poses(course):
    q = random_joints(3000, seed=41)
    T = course.fk(q)
    hints = _hints(course, np.where(np.arange(len(q))[:, None] % 2 == 0, q, random_joints(len(q), seed=42)))
    _assert_same(_batch(compiled, course, T, hints), _batch(_numpy_kernels, course, T, hints), "random")


@pytest.mark.parametrize("preset", Arm.UR_PRESETS)
def test_the_kernels_lanes_decide_as_one_pose_at_a_time(preset):
    """``ik_batch`` solves poses eight at a time, with an atan2 of its own, and leaves every pose
    with a slot near a singularity, a hint or a tolerance's edge to the one-pose steps: its flags
    and distances are theirs, its angles theirs to a few ulp (never ±π spelled differently), on
    random, partly unreachable, near- and exactly singular poses, at ±π, with and without hints."""
    arm = Arm.preset(preset)
    rng = np.random.default_rng(47)

    def near(n: int) -> np.ndarray:  # 0 or ±π, or 1e-16…1e-6 from one
        return rng.choice([0.0, math.pi, -math.pi], n) + rng.choice([-1, 0, 1], n) * 10.0 ** rng.uniform(-16, -6, n)

    q = random_joints(5500, seed=46)
    q[1000:1500, 4] = near(500)
    q[1500:2000, 2] = near(500)
    q[2000:2500] = arm.singular_configuration("shoulder", q[2000:2500])
    q[2500:3000, rng.integers(0, 6, 500)] = math.pi
    q[3500:5000, 2], q[3500:5000, 4] = near(1500), near(1500)  # elbow and wrist
    q[4000:5000] = arm.singular_configuration("shoulder", q[4000:5000])  # and the shoulder
    q, extra = q[:5000], q[5000:]
    extra[:250, 4] = near(250)  # half of them with the wrist singular too
    T = arm.fk(q)
    T[3000:3500, :3, 3] *= rng.uniform(0.0, 2.0, (500, 1))  # some out of reach, some inside the shoulder cylinder
    T[3500:, :3] += rng.integers(-2, 3, (1500, 3, 4)) * np.spacing(T[3500:, :3])  # up to 2 ulp off
    # stretched at the shoulder singularity and moved 1e-9…1e-3 m beyond the reach along the arm (a
    # shoulder reach within its band, or a wrist's turn, may then reach: one pose at a time decides)
    stretched = arm.singular_configuration("shoulder", np.column_stack([extra[:, :2], np.zeros(500), extra[:, 3:]]))
    geometry = arm.singularity_geometry(stretched)
    along = geometry.p4 - geometry.elbow_center
    T = np.concatenate([T, arm.fk(stretched)])
    T[5000:, :3, 3] += 10.0 ** rng.uniform(-9, -3, (500, 1)) * along / np.linalg.norm(along, axis=-1, keepdims=True)
    q = np.concatenate([q, stretched])
    others = random_joints(len(q), seed=48)
    elbow_and_reach = _hints(arm, q)
    elbow_and_reach[:, 0] = others[:, 5]  # the generating θ3 and A, another θ6: not the wrist's hint alone
    for hints in (np.tile([0.0, np.nan, np.nan], (len(q), 1)), _hints(arm, q), elbow_and_reach, _hints(arm, others)):
        lanes = _batch(compiled, arm, T, hints)
        ones = [_one(compiled, arm, T[k], hints[k]) for k in range(len(q))]
        for name in FIELDS:  # exactly equal (NaN to NaN); the angles to 1e-13
            batch, one = lanes[name], np.array([o[name] for o in ones])
            same = np.isclose(batch, one, rtol=0, atol=1e-13 if name == "q" else 0, equal_nan=True)
            differs = np.flatnonzero(~same.reshape(len(q), -1).all(axis=-1))
            assert not differs.size, \
                f"{name} differs at {differs.size} poses, the first {differs[0]}: {batch[differs[0]]} vs one at a time {one[differs[0]]}"


@pytest.mark.parametrize("preset", ["ur10", "ur10e"])
def test_backends_agree_at_the_triple_singularity(preset):
    """Elbow folded or stretched, wrist singular and the wrist centre on the d4 cylinder, each
    within 1e-16…1e-6 of exact, then the pose moved by up to 2 ulp: flags and failure codes
    equal, with no hint and with the generating joints (an issue's fuzz found 2 of 1.3 M apart)."""
    arm = Arm.preset(preset)
    rng = np.random.default_rng(43)
    n = 20000

    def offset(low: float, high: float) -> np.ndarray:
        return rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(low, high, n)

    q = random_joints(n, seed=44)
    q[:, 2] = rng.choice([0.0, np.pi, -np.pi], n) + offset(-16, -6)
    q[:, 4] = rng.choice([0.0, np.pi, -np.pi], n) + offset(-16, -6)
    t2, t3 = q[:, 1], q[:, 2]  # θ2 and θ4 so that the shoulder factor a2 c2 + a3 c23 − d5 s234 is tiny
    t2 = np.where(np.abs(arm.a2 * np.cos(t2) + arm.a3 * np.cos(t2 + t3)) > arm.d5,
                  np.arctan2(arm.a2 + arm.a3 * np.cos(t3), arm.a3 * np.sin(t3)), t2)
    ratio = (arm.a2 * np.cos(t2) + arm.a3 * np.cos(t2 + t3) - offset(-16, -7)) / arm.d5
    q[:, 1], q[:, 3] = t2, np.arcsin(np.clip(ratio, -1, 1)) - t2 - t3
    T = arm.fk(q)
    T[:, :3] += rng.integers(-2, 3, (n, 3, 4)) * np.spacing(T[:, :3])
    for hints in (np.tile([0.0, np.nan, np.nan], (n, 1)), _hints(arm, q)):
        c, m = _batch(compiled, arm, T, hints), _batch(_numpy_kernels, arm, T, hints)
        for name in ("valid", "failure", "wrist_singular", "elbow_singular", "shoulder_singular"):
            np.testing.assert_array_equal(c[name], m[name], err_msg=name)


def test_far_and_huge_poses_agree(course):
    T = np.tile(np.eye(4), (6, 1, 1))
    T[:, :3, 3] = [[2.5, 0.3, 0.4], [1e150] * 3, [1e300] * 3, [-1e308] * 3, [0.05, 0.02, 0.6], [0.0, 0.0, 0.0]]
    hints = np.tile([0.0, np.nan, np.nan], (6, 1))
    c, n = _batch(compiled, course, T, hints), _batch(_numpy_kernels, course, T, hints)
    for name in ("valid", "failure", "wrist_singular", "shoulder_singular"):
        np.testing.assert_array_equal(c[name], n[name])
    np.testing.assert_array_equal(np.isnan(c["elbow_distance"]), np.isnan(n["elbow_distance"]))


@pytest.mark.parametrize("angle", [0.0, math.pi, -math.pi, 3 * math.pi, 1e9, -1e9, 1e16, 1e300, -1e308, 5e-324])
def test_wrap_is_exact_and_the_same_everywhere(angle):
    expected = math.remainder(angle, 2 * math.pi)
    expected = expected + 2 * math.pi if expected <= -math.pi else expected
    assert ik_reference.wrap(angle) == expected
    assert float(_numpy_kernels.wrap(np.array(angle))) == expected
    arm = Arm.preset("course")
    # wrist singular with the elbow well inside its reach: every θ6 works, and the
    # wrapped hint comes back through each kernel
    T = arm.fk(np.array([0.4, -1.1, 1.3, 0.5, 0.0, 1.0]))
    assert compiled.ik_one(T, angle, math.nan, math.nan, arm.dh_lengths)[0][4, 5] == expected
    assert _numpy_kernels.ik_one(T, angle, math.nan, math.nan, arm.dh_lengths)[0][4, 5] == expected


def test_a_huge_hint_returns():
    """The old C wrap() subtracted 2π in a loop: 0.26 s at 1e9, forever (holding the GIL) from 1e16.

    In a process of its own, so that a hang is caught by the timeout (which only a hang
    reaches); how long a huge hint takes is a row of bench_core.
    """
    code = (
        "import numpy as np; from ur10core import Arm; a = Arm.preset('course'); T = a.fk(np.zeros(6));"
        "s = [a.ik(T, hint=[0, 0, 0, 0, 0, h]) for h in (1e9, 1e16, 1e300)];"
        "print(all(x.valid.any() and np.isfinite(x.q[x.valid]).all() for x in s))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=HANG_TIMEOUT, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True"


def test_jacobians_agree_one_pose_and_many(course):
    q = np.concatenate([random_joints(300, seed=45), np.zeros((1, 6))])
    J_c, J_n = np.empty((len(q), 6, 6)), np.empty((len(q), 6, 6))
    compiled.jacobians(q, course.dh_lengths, J_c)
    _numpy_kernels.jacobians(q, course.dh_lengths, J_n)
    np.testing.assert_allclose(J_c, J_n, rtol=0, atol=1e-14)
    for k in range(0, len(q), 30):
        for module in (compiled, _numpy_kernels):
            np.testing.assert_array_equal(module.jacobian_one(q[k], course.dh_lengths), (J_c if module is compiled else J_n)[k])
    for module in (compiled, _numpy_kernels):
        assert module.jacobian_one(np.array([0, 0, np.inf, 0, 0, 0]), course.dh_lengths) is None


def test_frames_fk_and_quaternions_agree(course):
    q = np.concatenate([random_joints(500, seed=43), np.radians([[45, 90, 0, -90, 0, 60], [0, 0, 0, 0, 0, 0]])])
    out_c, out_n = np.empty((len(q), 7, 4, 4)), np.empty((len(q), 7, 4, 4))
    compiled.frames(q, course.dh_lengths, out_c)
    _numpy_kernels.frames(q, course.dh_lengths, out_n)
    np.testing.assert_allclose(out_c, out_n, rtol=0, atol=1e-14)
    for k in range(0, len(q), 25):
        np.testing.assert_allclose(compiled.fk_one(q[k], course.dh_lengths), _numpy_kernels.fk_one(q[k], course.dh_lengths),
                                   rtol=0, atol=1e-15)
    assert compiled.fk_one(np.array([0, 0, 0, np.nan, 0, 0]), course.dh_lengths) is None
    assert _numpy_kernels.fk_one(np.array([0, 0, 0, np.nan, 0, 0]), course.dh_lengths) is None
    R = np.ascontiguousarray(out_c[:, 1:, :3, :3].reshape(-1, 3, 3))
    # rotations by exactly π about each axis take every branch of Shepperd's method
    R = np.concatenate([R, np.diag([1.0, -1.0, -1.0])[None], np.diag([-1.0, 1.0, -1.0])[None], np.diag([-1.0, -1.0, 1.0])[None]])
    w_c, w_n = np.empty((len(R), 4)), np.empty((len(R), 4))
    compiled.quaternions(R, w_c)
    _numpy_kernels.quaternions(R, w_n)
    np.testing.assert_allclose(w_c, w_n, rtol=0, atol=1e-15)
    # one at a time (the drag's calls take the numpy kernel's float path)
    for k in range(0, len(q), 10):
        one_c, one_n = np.empty((1, 7, 4, 4)), np.empty((1, 7, 4, 4))
        compiled.frames(q[k:k + 1], course.dh_lengths, one_c)
        _numpy_kernels.frames(q[k:k + 1], course.dh_lengths, one_n)
        np.testing.assert_allclose(one_c, one_n, rtol=0, atol=1e-14)
    for k in [*range(0, len(R) - 3, 50), *range(len(R) - 3, len(R))]:
        one_c, one_n = np.empty((1, 4)), np.empty((1, 4))
        compiled.quaternions(R[k:k + 1], one_c)
        _numpy_kernels.quaternions(R[k:k + 1], one_n)
        np.testing.assert_allclose(one_c, one_n, rtol=0, atol=1e-15)


def test_nearest_one_agrees(course):
    rng = np.random.default_rng(44)
    for k in range(400):
        q = random_joints(1, seed=300 + k)[0]
        solution = course.ik(course.fk(q))
        valid = solution.valid & (rng.random(8) < 0.8)
        current = q + rng.normal(scale=0.5, size=6) + 2 * np.pi * rng.integers(-3, 4, size=6)
        limit = [2 * np.pi, np.pi, 10.0][k % 3]
        prefer = int(rng.integers(-1, 8))
        args = (np.ascontiguousarray(solution.q), np.ascontiguousarray(valid), current, limit, prefer, 1e-10)
        slot_c, q_c = compiled.nearest_one(*args)
        slot_n, q_n = _numpy_kernels.nearest_one(*args)
        assert slot_c == slot_n
        np.testing.assert_allclose(q_c, q_n, rtol=0, atol=1e-12)
        if slot_c >= 0:
            assert (np.abs(q_c) <= limit).all()


def test_the_kernel_refuses_to_run_without_its_tolerances():
    """Loaded on its own (not through ur10core, which hands them over), the kernel will not guess them."""
    code = (
        "import importlib.util as u, numpy as np, sys; s = u.spec_from_file_location('_kernels', sys.argv[1]);"
        "k = u.module_from_spec(s); s.loader.exec_module(k); k.ik_one(np.eye(4), 0.0, float('nan'), float('nan'), (0.1,) * 6)"
    )
    done = subprocess.run([sys.executable, "-c", code, compiled.__file__], capture_output=True, text=True, timeout=HANG_TIMEOUT)
    assert "set_tolerances() was not called" in done.stderr


@pytest.mark.parametrize("requested, expected", [("numpy", "numpy"), ("compiled", "compiled"), ("", "compiled")])
def test_the_environment_variable_picks_the_backend(requested, expected):
    env = dict(os.environ, UR10CORE_BACKEND=requested)
    code = "import ur10core, ur10core.ik as ik, sys; print(ur10core.BACKEND, ik.kernels.__name__, 'ur10core._kernels' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=HANG_TIMEOUT, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    backend, module, compiled_imported = done.stdout.split()
    assert backend == expected
    assert module == ("ur10core._numpy_kernels" if expected == "numpy" else "ur10core._kernels")
    assert compiled_imported == str(expected == "compiled")  # forced numpy behaves as if it were not built


def test_a_misspelt_backend_is_refused():
    env = dict(os.environ, UR10CORE_BACKEND="fortran")
    done = subprocess.run([sys.executable, "-c", "import ur10core"], capture_output=True, text=True, env=env, timeout=HANG_TIMEOUT)
    assert done.returncode != 0 and "UR10CORE_BACKEND must be 'compiled' or 'numpy', got 'fortran'" in done.stderr


def test_one_tolerance_source():
    """No tolerance is written twice: the C file holds no literal of its own, and every other
    module of the core that names one takes it from ur10core/tolerances.py."""
    import re

    from ur10core import tolerances

    source = (ROOT / "ur10core" / "_kernels.c").read_text()
    assert not re.search(r"\b\d(\.\d+)?e-\d+\b", re.sub(r"/\*.*?\*/", "", source, flags=re.S)), "a literal tolerance in _kernels.c"
    names = [name for name in dir(tolerances) if name.isupper()]
    for module in (ROOT / "ur10core").rglob("*.py"):
        if module.name == "tolerances.py":
            continue
        for name in names:
            assert not re.search(rf"^\s*{name}\s*[:=]", module.read_text(), flags=re.M), f"{module.name} defines {name} again"
        own = re.findall(r"^(\w*TOLERANCE)\s*=", module.read_text(), flags=re.M)
        assert not own, f"{module.name} defines {own}: every tolerance belongs in tolerances.py"


def test_the_kernel_is_iso_c99_that_msvc_also_compiles():
    """No MSVC here, so hold the C to what MSVC's C compiler takes: strict ISO C99 (gcc's
    extensions are errors, no variable-length arrays, which MSVC never had), and none of the
    POSIX or gcc names MSVC lacks. Python.h defines M_PI on Linux, so a compile alone would
    not catch it."""
    import shutil
    import sysconfig
    import re

    source = (ROOT / "ur10core" / "_kernels.c").read_text()
    # the comments and docstrings may name what the code avoids
    code = re.sub(r'/\*.*?\*/|"(?:[^"\\]|\\.)*"', "", source, flags=re.S)
    for name in (r"M_\w+", r"__attribute__", r"__builtin_\w+", r"typeof", r"_Complex", r"alloca", r"sincos"):
        found = re.search(rf"\b{name}\b", code)
        assert found is None, f"_kernels.c uses {found.group()}, which MSVC does not have"
    compiler = shutil.which("gcc")
    if compiler is None:
        pytest.skip("no gcc to check the C with")
    done = subprocess.run(
        [compiler, "-std=c99", "-pedantic-errors", "-Werror=vla", "-Wall", "-Werror",
         "-fsyntax-only", "-isystem", sysconfig.get_paths()["include"], "-isystem", np.get_include(),
         str(ROOT / "ur10core" / "_kernels.c")],
        capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr


# ---------------------------------------------------------------------------- the spherical-wrist arms


@pytest.mark.parametrize("name", ["kr210", "elbow", "stanford"])
@pytest.mark.parametrize("kind", ["random", "near singular", "out of reach"])
def test_the_spherical_wrist_arms_compiled_decide_as_on_numpy(name, kind, monkeypatch):
    """``wrist_ik`` (C) against the solvers' numpy batch path, on the same poses and hints, one pose at
    a time and in a batch: the same slots valid, singular and failing, with the same numbers to rounding."""
    from ur10core.solvers import spherical_wrist

    from .test_serial_arms import near_singular_joints, random_joints, wrapped

    monkeypatch.setattr(spherical_wrist, "_WRIST_IK", compiled.wrist_ik)  # whichever backend this run is on
    arm = Arm.preset(name)
    n = 3000
    q = random_joints(arm, n, 31) if kind != "near singular" else near_singular_joints(arm, n, 32)
    T = arm.fk(q)
    if kind == "out of reach":
        T[:, :3, 3] *= np.random.default_rng(33).choice([0.05, 1.0, 3.0], n)[:, None]
    for hint in (None, q, random_joints(arm, n, 34)):
        reference = arm.solver.solve(T, hint)
        batch = arm.solver._compiled_ik(arm, T, hint)
        ones = [arm.solver._compiled_ik(arm, T[k], None if hint is None else hint[k]) for k in range(0, n, 30)]
        for key in ("valid", "failure") + (() if kind == "near singular" else ("singular",)):
            np.testing.assert_array_equal(getattr(batch, key), reference[key], err_msg=key)
            np.testing.assert_array_equal([getattr(one, key) for one in ones], reference[key][::30], err_msg=key)
        np.testing.assert_allclose(batch.detail, reference["detail"], rtol=1e-12, atol=1e-15)
        valid = batch.valid
        if kind != "near singular":
            np.testing.assert_allclose(wrapped(batch.q - reference["q"], arm.revolute)[valid], 0.0, atol=1e-9)
        assert arm.pose_error(np.where(valid[..., None], batch.q, 0.0), T[:, None])[valid].max() < 1e-9
        assert np.isnan(batch.q[~valid]).all()
        for one, k in zip(ones, range(0, n, 30)):
            np.testing.assert_array_equal(np.isnan(one.q), np.isnan(batch.q[k]))
            np.testing.assert_allclose(np.nan_to_num(one.q), np.nan_to_num(batch.q[k]), rtol=0, atol=0)


def test_the_spherical_wrist_kernel_refuses_what_is_not_a_pose(monkeypatch):
    from ur10core.solvers import spherical_wrist

    monkeypatch.setattr(spherical_wrist, "_WRIST_IK", compiled.wrist_ik)
    arm = Arm.preset("kr210")
    T = arm.fk(np.zeros((5, 6)))
    T[3, 0, 0] = 2.0
    with pytest.raises(ValueError, match=r"T\[3\]: rotation part is not orthonormal"):
        arm.solver._compiled_ik(arm, T)
    with pytest.raises(ValueError, match="hint of shape"):
        arm.solver._compiled_ik(arm, T, np.zeros((2, 6)))
    with pytest.raises(ValueError, match="shape"):
        arm.solver._compiled_ik(arm, np.eye(3))
    geometry = arm.solver.compiled_geometry()
    out = (np.empty((1, 8, 6)), np.empty((1, 8), bool), np.empty((1, 8), bool), np.empty((1, 8), np.int8), np.empty((1, 8)))
    with pytest.raises(ValueError, match="geometry"):
        compiled.wrist_ik(np.eye(4).reshape(1, 16), None, geometry[:-1], *out)
    with pytest.raises(ValueError, match="sizes"):
        compiled.wrist_ik(np.eye(4).reshape(1, 16), np.zeros((2, 6)), geometry, *out)
    with pytest.raises(TypeError, match="C-contiguous"):
        compiled.wrist_ik(np.eye(4).reshape(1, 16), None, geometry, np.empty((1, 8, 6), np.float32), *out[1:])
