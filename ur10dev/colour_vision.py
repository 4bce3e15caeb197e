"""Colour as students see it: CIELAB, simulated colour-vision deficiency, ghosts over the page.

Colour-vision deficiency is simulated with Machado, Oliveira & Fernandes (2009), severity 1,
in linear RGB; distances are CIE76 ΔE in CIELAB (D65). A ghost is seen at GHOST_OPACITY
over the page; a washed-out projector mixes 30 % white into everything.
"""

from __future__ import annotations

import itertools

import numpy as np

from ur10teach.style import PAGE_BACKGROUND

VISION = {
    "normal": np.eye(3),
    "protan": np.array([[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216], [-0.003882, -0.048116, 1.051998]]),
    "deutan": np.array([[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413], [-0.011820, 0.042940, 0.968881]]),
}
#: Smallest ΔE between any two ghosts. The palette before issue 15 had 0.5 (two ghosts the same to a deutan eye).
MIN_DELTA_E = 5.0


def linear(rgb) -> np.ndarray:
    c = np.asarray(rgb, float) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def cielab(linear_rgb: np.ndarray) -> np.ndarray:
    xyz = linear_rgb @ np.array([[0.4124, 0.2126, 0.0193], [0.3576, 0.7152, 0.1192], [0.1805, 0.0722, 0.9505]])
    xyz = xyz / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def seen(rgb, vision: str, opacity: float = 1.0, washed: float = 0.0) -> np.ndarray:
    mixed = opacity * linear(rgb) + (1 - opacity) * linear(PAGE_BACKGROUND)
    simulated = np.clip(mixed @ VISION[vision].T, 0, 1)
    return cielab((1 - washed) * simulated + washed)


def closest_pair(colours, opacity: float) -> tuple[float, int, int, str, float]:
    """(ΔE, branch a, branch b, vision, washed) of the two colours nearest each other in any condition."""
    return min(
        (float(np.linalg.norm(seen(colours[a], vision, opacity, washed) - seen(colours[b], vision, opacity, washed))),
         a + 1, b + 1, vision, washed)
        for vision in VISION for washed in (0.0, 0.3) for a, b in itertools.combinations(range(len(colours)), 2)
    )
