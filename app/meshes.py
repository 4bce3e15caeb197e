"""The link meshes: the schematic arm of ``assets/meshes/<preset>/`` (``scripts/build_meshes.py``)
and UR's real UR10 in ``assets/meshes/real/ur10/`` (``scripts/convert_ur_meshes.py``)."""

from __future__ import annotations

import functools
import importlib.resources
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

#: ``assets/meshes`` of the source tree, installed as the package data of ``ur10teach.assets``.
MESH_DIR = Path(str(importlib.resources.files("ur10teach.assets") / "meshes"))


@dataclass(frozen=True, eq=False)  # compared and hashed by identity: load_links hands out one per link
class LinkMesh:
    """Link i's geometry in its own DH frame {i}: aluminium body and blue joint cap."""

    index: int
    body_vertices: np.ndarray  #: (V, 3) float32, metres
    body_faces: np.ndarray  #: (F, 3) uint32
    cap_vertices: np.ndarray
    cap_faces: np.ndarray
    #: a coarser single mesh for the eight translucent ghosts; None: body and cap merged
    ghost_mesh: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def merged(self) -> tuple[np.ndarray, np.ndarray]:
        """Body and cap as one mesh."""
        faces = np.vstack([self.body_faces, self.cap_faces + len(self.body_vertices)])
        return np.vstack([self.body_vertices, self.cap_vertices]), faces

    @property
    def ghost(self) -> tuple[np.ndarray, np.ndarray]:
        """The single-colour mesh each ghost arm draws for this link."""
        return self.ghost_mesh if self.ghost_mesh is not None else self.merged


#: a link without a part (the UR10's link 3 has no joint cap)
_EMPTY = (np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32))


def _read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.load(path, process=False, force="mesh")
    if not isinstance(mesh, trimesh.Trimesh):  # a file of no faces: trimesh 4.0 reads it as an empty list
        return _EMPTY
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
        links.append(LinkMesh(i, *body, *_read(folder / f"link{i}_cap.ply")))
    return tuple(links)


REAL = "Real UR10"
SCHEMATIC = "Schematic"
#: The ghosts' default drawing (:func:`skeleton_links`): thick sticks and joint discs, unmistakably not the solid arm.
SKELETON = "Skeleton"
#: presets drawn with UR's UR10 meshes: the course's DH table rounds the UR10's to within 1 mm
REAL_MESHES = {"course": "ur10", "ur10": "ur10"}


def _parts(path: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    scene = trimesh.load(path, force="scene", process=False)
    return {name: (np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32).reshape(-1, 3))
            for name, mesh in scene.geometry.items()}


@functools.lru_cache(maxsize=None)
def load_real_links(model: str = "ur10", mesh_dir: Path = MESH_DIR) -> tuple[LinkMesh, ...]:
    """UR's meshes of ``model``, each in its DH frame, with a coarser ghost mesh per link."""
    folder = mesh_dir / "real" / model
    links = []
    for i in range(7):
        parts = _parts(folder / f"link{i}.glb")
        links.append(LinkMesh(i, *parts["body"], *parts.get("cap", _EMPTY), ghost_mesh=parts["ghost"]))
    return tuple(links)


@dataclass(frozen=True, eq=False)
class ArmModels:
    """The ways one arm can be drawn, by name (the first is the default), and how they are shaded.

    ``light`` (``--light``): toon shading and no shadows, as every browser's light view starts
    (``ur10teach.features.light_view``). Software WebGL, on a laptop without a graphics driver,
    draws the arm and its translucent ghosts with physically based shading, shadows and
    image-based lighting several times more slowly; without the environment map's light, toon
    shading keeps the ghosts' colours.
    """

    by_name: dict[str, tuple[LinkMesh, ...]]
    light: bool = False

    @property
    def material(self) -> str:
        """viser's material for the arm and its ghosts (:func:`material`)."""
        return material(self.light)

    @property
    def shadows(self) -> bool:
        return not self.light

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.by_name)

    @property
    def default(self) -> tuple[LinkMesh, ...]:
        return next(iter(self.by_name.values()))

    @property
    def outline(self) -> np.ndarray:
        """(7, P, 3) the default model's :func:`body_points`: the floor check tests the arm that would collide."""
        return body_points(self.default)


def material(light: bool) -> str:
    """viser's material for the arm and its ghosts, in the light view or out of it."""
    return "toon3" if light else "standard"


@functools.lru_cache(maxsize=None)
def load_models(preset: str, light: bool = False) -> ArmModels:
    """The real UR10 where the preset is one (and the schematic beside it), else the schematic alone;
    ``light`` draws the schematic first (a tenth of the real arm's triangles) and shades both for
    software WebGL (:class:`ArmModels`)."""
    schematic = load_links(preset)
    if preset in REAL_MESHES:
        real = load_real_links(REAL_MESHES[preset])
        return ArmModels({SCHEMATIC: schematic, REAL: real} if light else {REAL: real, SCHEMATIC: schematic}, light)
    return ArmModels({SCHEMATIC: schematic}, light)


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


@functools.lru_cache(maxsize=None)
def skeleton_links(table, stick: float = 0.018, disc: tuple[float, float] = (0.045, 0.03)) -> tuple[LinkMesh, ...]:
    """A ghost's links as its DH table builds them, each in its own frame {i} (modified DH, revolute joints).

    Link i is a stick from its origin along x_i by a_i, then along z_{i+1} by d_{i+1} to the
    next origin (both fixed in {i}: row i+1 turns only about z_{i+1}), and a disc on joint i's
    axis z_i; ``stick`` is the sticks' radius, ``disc`` the discs' radius and thickness (m).
    """
    links = []
    for i in range(7):
        parts = [trimesh.creation.cylinder(radius=disc[0], height=disc[1], sections=20)] if i else []
        if 0 < i < len(table.rows):
            row = table.rows[i]  # a_i, α_i and d_{i+1}
            corner = np.array([row.a, 0.0, 0.0])
            end = corner + row.d * np.array([0.0, -np.sin(row.alpha), np.cos(row.alpha)])
            parts += [trimesh.creation.cylinder(radius=stick, segment=(a, b), sections=10)
                      for a, b in ((np.zeros(3), corner), (corner, end)) if np.linalg.norm(b - a) > 1e-6]
        mesh = trimesh.util.concatenate(parts) if parts else trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), int))
        vertices, faces = np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32).reshape(-1, 3)
        links.append(LinkMesh(i, vertices, faces, *_EMPTY))
    return tuple(links)
