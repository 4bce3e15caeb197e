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


@dataclass(frozen=True, eq=False)  # compared and hashed by identity: load_links hands out one per link
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


@functools.lru_cache(maxsize=None)
def body_points(links: tuple[LinkMesh, ...], directions: int = 128) -> np.ndarray:
    """(7, P, 3): for each link, the vertices farthest out in ``directions`` directions (its outline).

    The floor check (``ArmState``) needs only each body's lowest point; these vertices
    contain it to within a fraction of a millimetre for any pose, at a fraction of the
    mesh's vertices. Shorter lists repeat their first point.
    """
    k = np.arange(directions) + 0.5  # a Fibonacci sphere: evenly spread directions
    polar, azimuth = np.arccos(1 - 2 * k / directions), np.pi * (1 + 5**0.5) * k
    unit = np.stack([np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], axis=1)
    outlines = []
    for link in links:
        vertices = link.merged[0].astype(float)
        outlines.append(vertices[np.unique(np.argmax(vertices @ unit.T, axis=0))])
    size = max(len(o) for o in outlines)
    return np.stack([np.vstack([o, np.repeat(o[:1], size - len(o), axis=0)]) for o in outlines])
