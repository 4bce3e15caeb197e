"""The link meshes in ``assets/meshes/<preset>/`` (built by ``scripts/build_meshes.py``)."""

from __future__ import annotations

import functools
import importlib.resources
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

#: ``assets/meshes`` of the source tree, installed as the package data of ``app.assets``.
MESH_DIR = Path(str(importlib.resources.files("app.assets") / "meshes"))


@dataclass(frozen=True)
class LinkMesh:
    """Link i's geometry in its own DH frame {i}: aluminium body and blue joint cap."""

    index: int
    body_vertices: np.ndarray  #: (V, 3) float32, metres
    body_faces: np.ndarray  #: (F, 3) uint32
    cap_vertices: np.ndarray
    cap_faces: np.ndarray

    @property
    def merged(self) -> tuple[np.ndarray, np.ndarray]:
        """Body and cap as one mesh (the single-colour ghost arms)."""
        faces = np.vstack([self.body_faces, self.cap_faces + len(self.body_vertices)])
        return np.vstack([self.body_vertices, self.cap_vertices]), faces


def _read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.load(path, process=False, force="mesh")
    return np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32).reshape(-1, 3)


@functools.lru_cache(maxsize=None)
def load_links(preset: str, mesh_dir: Path = MESH_DIR) -> tuple[LinkMesh, ...]:
    """The seven links of ``preset``; read once per process and shared by every client."""
    folder = mesh_dir / preset
    if not folder.is_dir():
        raise FileNotFoundError(f"no meshes for preset {preset!r} in {folder}; run python scripts/build_meshes.py")
    links = []
    for i in range(7):
        body = _read(folder / f"link{i}_body.ply")
        cap_path = folder / f"link{i}_cap.ply"
        cap = _read(cap_path) if cap_path.stat().st_size > 0 else (np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32))
        links.append(LinkMesh(i, *body, *cap))
    return tuple(links)
