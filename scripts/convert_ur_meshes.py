"""Convert Universal Robots' published UR10 visual meshes into the app's DH-framed GLB files.

    pip install trimesh pycollada fast-simplification     # build-time only
    python scripts/convert_ur_meshes.py PATH/TO/universal_robot/ur_description

writes ``assets/meshes/real/ur10/link<i>.glb`` (i = 0…6). Each file holds three meshes:
``body`` and ``cap`` for the solid arm (the caps are the parts UR colours blue) and a
coarser ``ghost`` for the eight translucent IK branches. Every vertex is expressed in the
link's own DH frame {i} (docs/kinematics.md §2), so the app places the real meshes exactly
as it places the schematic ones, with ``arm.frames(q)[i]``.

Source: ROS-Industrial ``universal_robot``, ``ur_description/meshes/ur10/visual/*.dae``
(BSD-3-Clause; see ``assets/meshes/real/ur10/LICENSE.md``). The mesh placement comes from
its ``urdf/inc/ur_macro.xacro`` (visual origins) and ``config/ur10/default_kinematics.yaml``
(joint origins), copied below. The transform from each URDF link frame to our DH frame is
not typed in: it is solved for, and checked to be constant over random joint vectors,
which fails loudly if the two chains ever disagree.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import sys
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ur10core import Arm  # noqa: E402

OUTPUT = ROOT / "assets" / "meshes" / "real" / "ur10"
SOURCE_FILES = ("base", "shoulder", "upperarm", "forearm", "wrist1", "wrist2", "wrist3")
CAP_COLOUR = (100, 138, 163)  # UR's blue end caps, as the .dae materials give them

#: Faces kept per link: the solid arm about 28 k in all, a ghost link 40 % of that.
SOLID_FACES = (1100, 4300, 6400, 6400, 4300, 4300, 900)
GHOST_FRACTION = 0.4

PI = np.pi
#: ur_description/config/ur10/default_kinematics.yaml: joint i's origin (xyz, rpy) in link i−1.
JOINT_ORIGINS = (
    ((0, 0, 0.1273), (0, 0, 0)),
    ((0, 0, 0), (1.570796327, 0, 0)),
    ((-0.612, 0, 0), (0, 0, 0)),
    ((-0.5723, 0, 0.163941), (0, 0, 0)),
    ((0, -0.1157, -2.373046667922381e-11), (1.570796327, 0, 0)),
    ((0, 0.0922, -1.891053610911353e-11), (1.570796326589793, PI, PI)),
)
#: ur_macro.xacro with config/ur10/{physical,visual}_parameters.yaml: each mesh's origin in its link.
VISUAL_ORIGINS = (
    ((0, 0, 0), (0, 0, PI)),
    ((0, 0, 0), (0, 0, PI)),
    ((0, 0, 0.220941), (PI / 2, 0, -PI / 2)),
    ((0, 0, 0.049042), (PI / 2, 0, -PI / 2)),
    ((0, 0, -0.1149), (PI / 2, 0, 0)),
    ((0, 0, -0.1158), (0, 0, 0)),
    ((0, 0, -0.0922), (PI / 2, 0, 0)),
)


def origin(xyz, rpy) -> np.ndarray:
    """URDF ``<origin>``: translate by xyz, then turn by R = Rz(yaw)·Ry(pitch)·Rx(roll)."""
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    transform = np.eye(4)
    transform[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    transform[:3, 3] = xyz
    return transform


def urdf_frames(q: np.ndarray, base: np.ndarray) -> np.ndarray:
    """(7, 4, 4) URDF link frames in our base frame; ``base`` places UR's ``base_link_inertia``."""
    frames = [base]
    for (xyz, rpy), angle in zip(JOINT_ORIGINS, q):
        turn = np.eye(4)
        turn[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
        frames.append(frames[-1] @ origin(xyz, rpy) @ turn)
    return np.stack(frames)


def dh_from_urdf(arm: Arm, samples: int = 50, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Constant X_i with F_dh_i(q) · X_i = F_urdf_i(s ⊙ q + o): each URDF link frame in DH frame {i}.

    Returns X (7, 4, 4) and the signs s and offsets o (6,) relating UR's joint angles to
    ours. Searched over the base turn (0 or π about z, preferring the one that needs no
    offset on joint 1) and, joint by joint, s_j = ±1 and o_j ∈ {0, ±π/2, π}. An offset
    only shows in the next link, so (s_j, o_j) must keep links j and j + 1 rigid.
    Rigid means constant to 1e-6: UR's yaml rounds π/2 to 1.570796327.
    """
    q = np.random.default_rng(seed).uniform(-PI, PI, (samples, 6))
    dh = arm.frames(q)
    choices = list(itertools.product((1.0, -1.0), (0.0, PI / 2, -PI / 2, PI)))

    def rigid(link: int, signs: np.ndarray, offsets: np.ndarray, base: np.ndarray) -> bool:
        urdf = np.stack([urdf_frames(signs * qi + offsets, base)[link] for qi in q])
        relative = np.linalg.inv(dh[:, link]) @ urdf
        return bool(np.abs(relative - relative[0]).max() < 1e-6)

    for base_turn in (PI, 0.0):
        base = origin((0, 0, 0), (0, 0, base_turn))
        signs, offsets = np.ones(6), np.zeros(6)
        for joint in range(6):
            for signs[joint], offsets[joint] in choices:
                if not rigid(joint + 1, signs, offsets, base):
                    continue
                if joint == 5 or any(rigid(joint + 2, np.r_[signs[:joint + 1], s, signs[joint + 2:]],
                                           np.r_[offsets[:joint + 1], o, offsets[joint + 2:]], base)
                                     for s, o in choices):
                    break
            else:
                break  # no choice for this joint: try the other base turn
        else:
            frames = urdf_frames(signs * q[0] + offsets, base)
            return np.linalg.inv(dh[0]) @ frames, signs, offsets
    raise RuntimeError("no joint mapping makes the URDF links rigid in the DH frames: do the two chains describe the same arm?")


def read_parts(path: Path) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """(body, cap) of a UR .dae, split by material: the caps are the blue parts."""
    scene = trimesh.load(path, force="scene")
    body, cap = [], []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        mesh = scene.geometry[name].copy()
        mesh.apply_transform(transform)
        colour = tuple(int(c) for c in mesh.visual.material.baseColorFactor[:3])
        (cap if colour == CAP_COLOUR else body).append(trimesh.Trimesh(mesh.vertices, mesh.faces))
    return trimesh.util.concatenate(body), (trimesh.util.concatenate(cap) if cap else trimesh.Trimesh())


def decimate(mesh: trimesh.Trimesh, faces: int) -> trimesh.Trimesh:
    if len(mesh.faces) <= faces:
        return mesh
    return mesh.simplify_quadric_decimation(face_count=faces)


def convert(source: Path, output: Path = OUTPUT) -> list[Path]:
    arm = Arm.preset("ur10")
    to_dh, signs, offsets = dh_from_urdf(arm)
    print(f"UR joint angles = {signs.astype(int).tolist()} ⊙ q + {np.degrees(offsets).round().tolist()}°")
    output.mkdir(parents=True, exist_ok=True)
    written = []
    for i, name in enumerate(SOURCE_FILES):
        placement = to_dh[i] @ origin(*VISUAL_ORIGINS[i])
        body, cap = read_parts(source / "meshes" / "ur10" / "visual" / f"{name}.dae")
        share = len(body.faces) / (len(body.faces) + len(cap.faces))
        body = decimate(body, round(SOLID_FACES[i] * share))
        cap = decimate(cap, round(SOLID_FACES[i] * (1 - share))) if len(cap.faces) else cap
        ghost = decimate(trimesh.util.concatenate([body, cap]), round(SOLID_FACES[i] * GHOST_FRACTION))
        scene = trimesh.Scene()
        for part, mesh in (("body", body), ("cap", cap), ("ghost", ghost)):
            if len(mesh.faces):
                mesh = trimesh.Trimesh(mesh.vertices, mesh.faces, process=True)
                mesh.apply_transform(placement)
                mesh.vertices = np.round(mesh.vertices, 6)
                scene.add_geometry(mesh, geom_name=part, node_name=part)
        path = output / f"link{i}.glb"
        path.write_bytes(scene.export(file_type="glb"))
        written.append(path)
    return written


def fingerprint(source: Path) -> str:
    """sha256 of the seven source files, recorded in LICENSE.md beside the meshes so a rebuild can be checked."""
    digest = hashlib.sha256()
    for name in SOURCE_FILES:
        digest.update((source / "meshes" / "ur10" / "visual" / f"{name}.dae").read_bytes())
    return digest.hexdigest()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ur_description", type=Path, help="the ur_description folder of a universal_robot checkout")
    parser.add_argument("--output", type=Path, default=OUTPUT)
    args = parser.parse_args(argv)
    paths = convert(args.ur_description, args.output)
    size = sum(p.stat().st_size for p in paths)
    print(f"{len(paths)} files, {size / 1024:.0f} KiB in {args.output}; sources sha256 {fingerprint(args.ur_description)}")


if __name__ == "__main__":
    main()
