"""Build the UR10-looking link meshes from the DH dimensions (trimesh primitives).

    python scripts/build_meshes.py            # writes assets/meshes/<preset>/link<i>_{body,cap}.ply

Every link i is modelled in its own DH frame {i} (docs/kinematics.md §2), so the app places
it with ``arm.frames(q)[i]``. Each link has a light-grey aluminium ``body`` and the
dark-blue joint ``cap`` people recognise from the real arm. Sizes follow the UR10:
base Ø190 mm, joint housings of Ø150 (base, shoulder), Ø120 (elbow) and Ø90 (wrist),
the upper arm offset 176 mm along the shoulder axis and the forearm 128 mm back, so
that the wrist-1 centre lands at d4 as the DH table says.

The committed files are what the app loads; ``tests/test_meshes.py`` checks that this
script still reproduces them exactly.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ur10core import Arm  # noqa: E402

OUTPUT = ROOT / "assets" / "meshes"
SECTIONS = 40  # facets around a cylinder: smooth enough on a projector, light to send

BASE_RADIUS = 0.095  # Ø190 mm footprint
BASE_PLATE = 0.015
SHOULDER_RADIUS = 0.075
ELBOW_RADIUS = 0.060
WRIST_RADIUS = 0.045
UPPER_ARM_RADIUS = 0.054
FOREARM_RADIUS = 0.040
FLANGE_RADIUS = 0.0315  # Ø63 mm tool flange
CAP_THICKNESS = 0.006
UPPER_ARM_OFFSET = 0.176  # along the shoulder axis z2
ELBOW_OFFSET = 0.128  # the forearm steps back towards the base by this much


def _cylinder(radius: float, start, end, sections: int = SECTIONS) -> trimesh.Trimesh:
    """A closed cylinder between two points."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    return trimesh.creation.cylinder(radius=radius, segment=np.stack([start, end]), sections=sections)


def _housing(radius: float, axis, centre, low: float, high: float) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A joint housing along ``axis`` from ``low`` to ``high`` about ``centre``, with a blue cap at ``high``."""
    axis, centre = np.asarray(axis, float), np.asarray(centre, float)
    body = _cylinder(radius, centre + low * axis, centre + (high - CAP_THICKNESS) * axis)
    cap = _cylinder(radius * 1.002, centre + (high - CAP_THICKNESS) * axis, centre + high * axis)
    return body, cap


def link_meshes(arm: Arm) -> dict[int, tuple[trimesh.Trimesh, trimesh.Trimesh]]:
    """Body and cap mesh of links 0..6, each in its own DH frame."""
    d1, a2, a3, d4, d5, d6 = arm.dh_lengths
    x, y, z = np.eye(3)
    forearm_offset = UPPER_ARM_OFFSET - ELBOW_OFFSET
    meshes: dict[int, tuple[list, list]] = {i: ([], []) for i in range(7)}

    # link 0, the base: mounting plate and the fixed part of the base joint
    base_top = d1 - SHOULDER_RADIUS - 0.02
    meshes[0][0].append(_cylinder(BASE_RADIUS, (0, 0, 0), (0, 0, BASE_PLATE)))
    meshes[0][0].append(_cylinder(SHOULDER_RADIUS, (0, 0, BASE_PLATE), (0, 0, base_top - 0.008)))
    meshes[0][1].append(_cylinder(SHOULDER_RADIUS * 1.01, (0, 0, base_top - 0.008), (0, 0, base_top)))

    # link 1 (frame {1} at shoulder height, z1 up; the shoulder axis z2 is -y1)
    meshes[1][0].append(_cylinder(SHOULDER_RADIUS, (0, 0, base_top - d1), (0, 0, 0)))
    body, cap = _housing(SHOULDER_RADIUS, -y, (0, 0, 0), -SHOULDER_RADIUS * 0.6, UPPER_ARM_OFFSET + SHOULDER_RADIUS)
    meshes[1][0].append(body)
    meshes[1][1].append(cap)

    # link 2 (frame {2}: x2 along the upper arm, z2 along the shoulder axis)
    meshes[2][0].append(_cylinder(UPPER_ARM_RADIUS, (0.0, 0, UPPER_ARM_OFFSET), (a2, 0, UPPER_ARM_OFFSET)))
    body, cap = _housing(ELBOW_RADIUS, z, (a2, 0, 0), forearm_offset - ELBOW_RADIUS, UPPER_ARM_OFFSET + ELBOW_RADIUS)
    meshes[2][0].append(body)
    meshes[2][1].append(cap)

    # link 3 (frame {3} at the elbow: x3 along the forearm) and the wrist-1 housing at its end
    meshes[3][0].append(_cylinder(FOREARM_RADIUS, (0.0, 0, forearm_offset), (a3, 0, forearm_offset)))
    meshes[3][0].append(_cylinder(WRIST_RADIUS, (a3, 0, forearm_offset - WRIST_RADIUS), (a3, 0, d4 - WRIST_RADIUS)))

    # link 4 (frame {4} at the wrist-1 centre; joint 5 turns about y4, 'up' the wrist)
    body, cap = _housing(WRIST_RADIUS, z, (0, 0, 0), -WRIST_RADIUS, WRIST_RADIUS)
    meshes[4][0].append(body)
    meshes[4][1].append(cap)
    meshes[4][0].append(_cylinder(WRIST_RADIUS, (0, WRIST_RADIUS * 0.5, 0), (0, d5 - WRIST_RADIUS, 0)))

    # link 5 (frame {5} at the wrist-2 point; z5 = y4, the tool axis z6 is -y5)
    body, cap = _housing(WRIST_RADIUS, z, (0, 0, 0), -WRIST_RADIUS, WRIST_RADIUS)
    meshes[5][0].append(body)
    meshes[5][1].append(cap)
    meshes[5][0].append(_cylinder(WRIST_RADIUS, (0, -WRIST_RADIUS * 0.5, 0), (0, -(d6 - 0.012), 0)))

    # link 6 (frame {6} at the flange, z6 out of the tool face)
    meshes[6][1].append(_cylinder(WRIST_RADIUS * 1.01, (0, 0, -0.012 - CAP_THICKNESS), (0, 0, -0.012)))
    meshes[6][0].append(_cylinder(FLANGE_RADIUS, (0, 0, -0.012), (0, 0, 0)))

    return {
        i: (trimesh.util.concatenate(body), trimesh.util.concatenate(cap) if cap else trimesh.Trimesh())
        for i, (body, cap) in meshes.items()
    }


def split_sharp_edges(mesh: trimesh.Trimesh, crease_degrees: float = 30.0) -> trimesh.Trimesh:
    """One vertex per (vertex, group of its faces whose normals lie within ``crease_degrees``).

    The browser averages the normals of the faces sharing a vertex: splitting vertices
    where a cylinder's side meets its caps keeps the rims crisp while the sides stay
    smooth. (trimesh's ``smooth_shaded`` does this too, but needs scipy or networkx.)
    """
    normals = mesh.face_normals
    cos_crease = np.cos(np.radians(crease_degrees))
    vertices, faces = [], np.empty_like(mesh.faces)
    for vertex in range(len(mesh.vertices)):
        face_index, corner = np.nonzero(mesh.faces == vertex)
        groups: list[np.ndarray] = []  # the first normal of each group
        for f, c in zip(face_index, corner):
            for g, reference in enumerate(groups):
                if normals[f] @ reference >= cos_crease:
                    break
            else:
                g = len(groups)
                groups.append(normals[f])
                vertices.append(mesh.vertices[vertex])
            faces[f, c] = len(vertices) - len(groups) + g
    return trimesh.Trimesh(vertices=np.array(vertices), faces=faces, process=False)


def write(preset: str, output: Path = OUTPUT) -> list[Path]:
    folder = output / preset
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for i, (body, cap) in link_meshes(Arm.preset(preset)).items():
        for part, mesh in (("body", body), ("cap", cap)):
            path = folder / f"link{i}_{part}.ply"
            if len(mesh.faces):
                mesh = split_sharp_edges(mesh)
            mesh = trimesh.Trimesh(vertices=np.round(mesh.vertices, 7).astype(np.float32), faces=mesh.faces, process=False)
            path.write_bytes(trimesh.exchange.ply.export_ply(mesh, encoding="binary", include_attributes=False))
            written.append(path)
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=OUTPUT)
    args = parser.parse_args(argv)
    for preset in Arm.UR_PRESETS:
        paths = write(preset, args.output)
        size = sum(p.stat().st_size for p in paths)
        print(f"{preset}: {len(paths)} files, {size / 1024:.0f} KiB in {paths[0].parent}")


if __name__ == "__main__":
    main()
