"""det J of the course's other arms, derived with sympy from each preset's DH table (docs/kinematics.md §7.6).

As for the UR10 (:mod:`ur10core.symbolic`), the derivation takes seconds (about 10 s for all
arms), so it is cached in ``symbolic_arms_cache.json``; :func:`load` reads it and the
test-suite checks the cache against a fresh :func:`derive`. Regenerate it with
``python -m ur10core.symbolic_arms --write-cache``.

How the determinant is split
----------------------------
Moving the reference point of the linear velocity multiplies J by a block-triangular
matrix of determinant 1, so det J can be taken at any point. For an arm with a spherical
wrist it is taken at the wrist centre: joints 4–6 no longer move that point, J is block
triangular and ``det J = det J_v(joints 1–3) · det J_ω(joints 4–6)``. Each block is then
checked to equal the product of factors with a geometric meaning (:data:`MEANINGS`),
times a constant:

* articulated arms (KR210, elbow arm): ρ (the wrist centre's distance from axis 1: the
  shoulder singularity), e (the forearm's reach across the upper arm, ``a2 · L sin β``:
  zero stretched or folded) and s5 (axes 4 and 6 in line);
* Stanford arm: d3² (the wrist centre on the shoulder), s2 (the boom parallel to axis 1,
  the wrist centre on the d2 cylinder: both shoulder branches meet) and s5;
* SCARA and planar elbow: s2 (stretched or folded); cylindrical: d3 (on the column), and s5 with
  its wrist.

Example
-------
>>> d = load("stanford")
>>> [(f.name, str(f.expression)) for f in d.factors]
[('stroke', 'q3**2'), ('shoulder', 'sin(q2)'), ('wrist', 'sin(q5)')]
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import inspect
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy as sp

from .arm import Arm
from .serial import PRESETS
from .symbolic import vanishes

CACHE_PATH = Path(__file__).with_name("symbolic_arms_cache.json")

#: What each factor means, per preset: (name, what makes it zero, in words for the app).
MEANINGS: dict[str, tuple[tuple[str, str], ...]] = {
    "kr210": (("shoulder", "the wrist centre is on axis 1: θ1 no longer moves it"),
              ("elbow", "upper arm and forearm are in line (stretched or folded): the wrist centre cannot move along the arm"),
              ("wrist", "θ5 = 0: axes 4 and 6 in line, only θ4 + θ6 counts")),
    "elbow": (("shoulder", "the wrist centre is on axis 1: θ1 no longer moves it"),
              ("elbow", "upper arm and forearm are in line (stretched or folded): the wrist centre cannot move along the arm"),
              ("wrist", "θ5 = 0: axes 4 and 6 in line, only θ4 + θ6 counts")),
    "stanford": (("stroke", "d3 = 0: the wrist centre on the shoulder, θ2 no longer moves it"),
                 ("shoulder", "θ2 = 0 or 180°: the boom along axis 1, the wrist centre on the d2 cylinder (both shoulder branches meet)"),
                 ("wrist", "θ5 = 0: axes 4 and 6 in line, only θ4 + θ6 counts")),
    "scara": (("elbow", "θ2 = 0 or 180°: the two links in line (stretched or folded)"),),
    "planar_elbow": (("elbow", "θ2 = 0 or 180°: the two links in line (stretched or folded)"),),
    "cylindrical": (("reach", "d3 = 0: the tool on the column's axis, θ1 no longer moves it"),),
    "cylindrical_wrist": (("reach", "d3 = 0: the wrist centre on the column's axis, θ1 no longer moves it"),
                          ("wrist", "θ5 = 0: axes 4 and 6 in line, only θ4 + θ6 counts")),
}


def mathml(expression: sp.Expr, joint_types: str) -> str:
    """Inline presentation MathML of a factor, in the course's joint names: θ_i for a revolute joint
    q_i, d_i for a prismatic one (sympy's own printer, which the browser renders).

    >>> mathml(sp.Symbol("q3") ** 2, "RRP")
    '<math><msup><msub><mi>d</mi><mi>3</mi></msub><mn>2</mn></msup></math>'
    """
    names = {f"q{i + 1}": sp.Symbol(f"{'θ' if kind == 'R' else 'd'}_{i + 1}") for i, kind in enumerate(joint_types)}
    renamed = expression.xreplace({symbol: names[symbol.name] for symbol in expression.free_symbols if symbol.name in names})
    return f"<math>{sp.printing.mathml(renamed, printer='presentation')}</math>"


def joint_symbols(n: int) -> tuple[sp.Symbol, ...]:
    return sp.symbols(f"q1:{n + 1}", real=True)


def _exact(value: float) -> sp.Expr:
    """A table's float as sympy sees it: π/2 as π/2, 0.35 as 7/20."""
    return sp.nsimplify(value, [sp.pi], tolerance=1e-12, rational=False)


def symbolic_frames(arm: Arm) -> list[sp.Matrix]:
    """T0i for every row, in the joint symbols q1..qn (the table's own convention, §7.1), as multiplied.

    Not simplified: what is proved of them goes through :func:`vanishes`, which expands anyway
    (simplifying every frame took 25 s for the KR210 alone).
    """
    table = arm.dh
    q = joint_symbols(table.n_joints)
    frames = [sp.eye(4)]
    joint = 0
    for row in table.rows:
        a, alpha, d, theta = (_exact(v) for v in (row.a, row.alpha, row.d, row.theta))
        if row.joint == "R":
            theta, joint = theta + q[joint], joint + 1
        elif row.joint == "P":
            d, joint = d + q[joint], joint + 1
        ca, sa, ct, st = sp.cos(alpha), sp.sin(alpha), sp.cos(theta), sp.sin(theta)
        if table.convention == "standard":
            A = sp.Matrix([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])
        else:
            A = sp.Matrix([[ct, -st, 0, a], [st * ca, ct * ca, -sa, -sa * d], [st * sa, ct * sa, ca, ca * d], [0, 0, 0, 1]])
        frames.append(frames[-1] * A)
    return frames


@dataclass(frozen=True)
class Factor:
    name: str  #: "shoulder", "elbow", "wrist", ...
    expression: sp.Expr  #: in q1..qn
    meaning: str  #: what makes it zero


@dataclass(frozen=True)
class ArmDerivation:
    """det J of one preset: ``det_J = constant · Π factors``."""

    name: str
    constant: sp.Expr
    factors: tuple[Factor, ...]

    @property
    def det_J(self) -> sp.Expr:
        return self.constant * sp.Mul(*(f.expression for f in self.factors))

    @functools.cached_property
    def _functions(self):
        n = Arm.preset(self.name).n_joints
        q = joint_symbols(n)
        return [sp.lambdify([q], f.expression, "numpy") for f in self.factors]

    def evaluate(self, q) -> np.ndarray:
        """The factors' values at joints ``q`` (..., n), shape (..., k)."""
        q = np.asarray(q, dtype=float)
        columns = [np.broadcast_to(function(np.moveaxis(q, -1, 0)), q.shape[:-1]) for function in self._functions]
        return np.stack(columns, axis=-1)


def _jacobian_blocks(arm: Arm, frames: list[sp.Matrix]) -> list[sp.Matrix]:
    """The square blocks whose determinants multiply to det J (module docstring)."""
    table = arm.dh
    index = [k if table.convention == "standard" else k + 1 for k in table.joint_rows]
    n = table.n_joints
    point = frames[arm.solver.wrist.first_row + 1][:3, 3] if arm.task == "pose" else frames[-1][:3, 3]
    Jv, Jw = sp.zeros(3, n), sp.zeros(3, n)
    for column, k in enumerate(index):
        z, o = frames[k][:3, 2], frames[k][:3, 3]
        if table.joint_types[column] == "R":
            Jv[:, column], Jw[:, column] = z.cross(point - o), z
        else:
            Jv[:, column] = z
    if arm.task == "pose":
        assert all(vanishes(entry, joint_symbols(n)) for entry in Jv[:, 3:]), "the wrist joints move the wrist centre"
        return [Jv[:, :3], Jw[:, 3:]]
    if arm.task == "position and yaw":
        return [Jv.col_join(Jw[2, :])]
    return [Jv[:2, :]] if n == 2 else [Jv]


def _expected_factors(arm: Arm, frames: list[sp.Matrix]) -> list[sp.Expr]:
    """The factors with a meaning, written from the geometry (module docstring)."""
    q = joint_symbols(arm.n_joints)
    if arm.name in ("kr210", "elbow"):
        table = arm.dh
        index = [k if table.convention == "standard" else k + 1 for k in table.joint_rows]
        centre = frames[arm.solver.wrist.first_row + 1][:3, 3]
        shoulder, elbow = frames[index[1]][:3, 3], frames[index[2]][:3, 3]
        heading = sp.Matrix([sp.cos(q[0]), sp.sin(q[0]), 0])
        rho = sp.simplify(centre.dot(heading))
        axis = frames[index[1]][:3, 2]
        reach_across = sp.simplify((elbow - shoulder).cross(centre - elbow).dot(axis))
        return [rho, reach_across, sp.sin(q[4])]
    if arm.name == "stanford":
        return [q[2] ** 2, sp.sin(q[1]), sp.sin(q[4])]
    if arm.name in ("scara", "planar_elbow"):
        return [sp.sin(q[1])]
    if arm.name == "cylindrical":
        return [q[2]]
    if arm.name == "cylindrical_wrist":
        return [q[2], sp.sin(q[4])]
    raise ValueError(f"no factored form is written for {arm.name!r}")


def derive(name: str) -> ArmDerivation:
    """det J of preset ``name``, proved to be a constant times its meaningful factors; up to a few seconds."""
    arm = Arm.preset(name)
    frames = symbolic_frames(arm)
    det = sp.Mul(*(block.det(method="berkowitz") for block in _jacobian_blocks(arm, frames)))
    factors = _expected_factors(arm, frames)
    q = joint_symbols(arm.n_joints)
    ratio = sp.lambdify([q], det / sp.Mul(*factors))
    # the constant, read at a generic pose and made exact; then the identity is proved symbolically
    constant = sp.nsimplify(float(ratio(np.linspace(0.31, 1.37, arm.n_joints) + 0.1)), tolerance=1e-10, rational=True)
    assert constant != 0, f"{name}: det J vanishes identically"
    assert vanishes(det - constant * sp.Mul(*factors), q), f"{name}: det J is not {constant} × the factors"
    meanings = MEANINGS[name]
    return ArmDerivation(name, constant, tuple(Factor(label, f, words) for (label, words), f in zip(meanings, factors)))


def _source_fingerprint() -> str:
    source = "".join(inspect.getsource(f) for f in (derive, vanishes, _expected_factors, _jacobian_blocks, symbolic_frames))
    source += repr({name: (spec.rows, spec.convention) for name, spec in PRESETS.items()})
    return hashlib.sha256(source.encode()).hexdigest()[:16]


def write_cache(path: Path = CACHE_PATH) -> Path:
    data = {"fingerprint": _source_fingerprint(), "sympy": sp.__version__, "arms": {}}
    for name in PRESETS:
        derivation = derive(name)
        data["arms"][name] = {"constant": sp.srepr(derivation.constant),
                              "factors": [[f.name, sp.srepr(f.expression)] for f in derivation.factors]}
    path.write_text(json.dumps(data, indent=1) + "\n")
    return path


@functools.lru_cache(maxsize=None)
def _cache(path: Path = CACHE_PATH) -> dict:
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise RuntimeError(f"{path} is missing; run python -m ur10core.symbolic_arms --write-cache") from None
    if data.get("fingerprint") != _source_fingerprint():
        raise RuntimeError(f"{path} is stale (the derivation changed); run python -m ur10core.symbolic_arms --write-cache")
    return data


@functools.lru_cache(maxsize=None)
def load(name: str, path: Path = CACHE_PATH) -> ArmDerivation:
    """The cached derivation of preset ``name`` (milliseconds)."""
    arms = _cache(path)["arms"]
    if name not in arms:
        raise ValueError(f"no derivation for {name!r}; presets: {', '.join(arms)}")
    entry = arms[name]
    meanings = dict(MEANINGS[name])
    return ArmDerivation(name, sp.sympify(entry["constant"]), tuple(
        Factor(label, sp.sympify(expression), meanings[label]) for label, expression in entry["factors"]))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write-cache", action="store_true", help=f"derive and write {CACHE_PATH.name}")
    if parser.parse_args(argv).write_cache:
        print(f"wrote {write_cache()}")
    else:
        for name in PRESETS:
            d = load(name)
            print(f"{name}: det J = {d.constant} · " + " · ".join(f"({f.expression})" for f in d.factors))


if __name__ == "__main__":
    main()
