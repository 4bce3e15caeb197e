"""T06, the Jacobian and det J derived with sympy from the DH table (docs/kinematics.md §2, §3, §5).

The derivation takes about fifteen seconds (sympy's ``trigsimp``), so the app never runs it:
:func:`load` reads the result cached in ``symbolic_cache.json`` (milliseconds), and the
test-suite checks that the cache equals a fresh :func:`derive`. Regenerate the cache
after changing the derivation with ``python -m ur10core.symbolic --write-cache``.

How det J is shown to factor
----------------------------
Expanding the 6x6 determinant of the base-frame Jacobian directly is hopeless, so the
derivation uses the two changes that leave det J unchanged:

* express every column in frame {1} (a block-diagonal rotation, determinant 1), and
* take the linear velocity at the wrist-2 point P5 instead of the flange origin
  (a block-triangular shift, determinant 1). P5 lies on axes 5 and 6, so their
  columns lose their linear part.

``J = M J_wrist`` with ``M = [[R01, -[o6 - o5]x R01], [0, R01]]`` is proved
symbolically, ``det M = det(R01)^2 = 1``, and ``det J_wrist`` is proved equal to

    det J = a2 · a3 · (a2 c2 + a3 c23 − d5 s234) · s3 · s5.

Example
-------
>>> d = load()
>>> str(d.det_J)
'a2*a3*(a2*cos(theta2) + a3*cos(theta2 + theta3) - d5*sin(theta2 + theta3 + theta4))*sin(theta3)*sin(theta5)'
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import inspect
import json
from dataclasses import dataclass
from pathlib import Path

import sympy as sp

CACHE_PATH = Path(__file__).with_name("symbolic_cache.json")

THETA = sp.symbols("theta1:7", real=True)
d1, a2, a3, d4, d5, d6 = LENGTHS = sp.symbols("d1 a2 a3 d4 d5 d6", positive=True)
#: (alpha_{i-1}, a_{i-1}, d_i) of the course's modified DH table, i = 1..6.
DH_TABLE = (
    (0, 0, d1),
    (sp.pi / 2, 0, 0),
    (0, a2, 0),
    (0, a3, d4),
    (-sp.pi / 2, 0, d5),
    (sp.pi / 2, 0, d6),
)


def _c(*joints: int) -> sp.Expr:
    return sp.cos(sum(THETA[j - 1] for j in joints))


def _s(*joints: int) -> sp.Expr:
    return sp.sin(sum(THETA[j - 1] for j in joints))


#: The three factors of det J as the course writes them (docs/kinematics.md §5).
SHOULDER_FACTOR = a2 * _c(2) + a3 * _c(2, 3) - d5 * _s(2, 3, 4)
ELBOW_FACTOR = _s(3)
WRIST_FACTOR = _s(5)
FACTORED_DET_J = a2 * a3 * SHOULDER_FACTOR * ELBOW_FACTOR * WRIST_FACTOR


@dataclass(frozen=True)
class Derivation:
    """The symbolic results (sympy expressions in ``THETA`` and ``LENGTHS``)."""

    T06: sp.Matrix  #: 4x4 base → flange, simplified entry by entry
    J: sp.Matrix  #: 6x6 geometric Jacobian, base frame, flange origin, rows [v; w]
    J_wrist: sp.Matrix  #: the same in frame {1}, linear velocity at P5
    det_J: sp.Expr  #: factored determinant

    def latex(self, name: str = "det_J") -> str:
        """LaTeX of one field, in the course's shorthand (c23 for cos(θ2+θ3), ...)."""
        return sp.latex(compact(getattr(self, name)))

    def mathml(self, name: str = "det_J") -> str:
        """Presentation MathML of one field inside ``<math display="block">`` (renders in browsers)."""
        return mathml(getattr(self, name))


def link_transform(alpha, a, theta, d) -> sp.Matrix:
    """``RotX(alpha) TransX(a) RotZ(theta) TransZ(d)`` (docs/kinematics.md §2, Craig form)."""
    ca, sa, ct, st = sp.cos(alpha), sp.sin(alpha), sp.cos(theta), sp.sin(theta)
    return sp.Matrix(
        [
            [ct, -st, 0, a],
            [st * ca, ct * ca, -sa, -sa * d],
            [st * sa, ct * sa, ca, ca * d],
            [0, 0, 0, 1],
        ]
    )


def _tidy(expression: sp.Expr) -> sp.Expr:
    """Expanded, then sums of angles gathered (c2 c3 − s2 s3 → c23): seconds where ``simplify`` takes a minute."""
    return sp.trigsimp(sp.expand(expression))


def frames() -> list[sp.Matrix]:
    """T0i for i = 0..6 from the DH table, each product tidied (:func:`_tidy`) before the next."""
    out = [sp.eye(4)]
    for (alpha, a, d), theta in zip(DH_TABLE, THETA):
        out.append((out[-1] * link_transform(alpha, a, theta, d)).applyfunc(_tidy))
    return out


def _cross_matrix(v: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def vanishes(expression: sp.Expr, angles) -> bool:
    """Whether a trigonometric polynomial in ``angles`` (and other symbols) is identically zero.

    Expanded to sines and cosines of single angles, it becomes a polynomial in (s_i, c_i);
    it is zero exactly when its remainder modulo s_i² + c_i² − 1 is (these relations, one
    per angle in its own variables, already form a Gröbner basis). Exact, and far faster
    than asking ``simplify`` for 0.

    >>> x, y = sp.symbols("x y", real=True)
    >>> vanishes(sp.sin(x + y) - sp.sin(x) * sp.cos(y) - sp.cos(x) * sp.sin(y), (x, y)), vanishes(sp.sin(x), (x,))
    (True, False)
    """
    angles = tuple(angles)
    s_, c_ = sp.symbols(f"s1:{len(angles) + 1}"), sp.symbols(f"c1:{len(angles) + 1}")
    polynomial = sp.expand(sp.expand_trig(sp.expand(expression))).subs(
        {**{sp.sin(x): si for x, si in zip(angles, s_)}, **{sp.cos(x): ci for x, ci in zip(angles, c_)}})
    relations = [si ** 2 + ci ** 2 - 1 for si, ci in zip(s_, c_)]
    _, remainder = sp.reduced(sp.expand(polynomial), relations, *s_, *c_, *angles)
    return sp.expand(remainder) == 0


def derive() -> Derivation:
    """Derive T06, J and det J from the DH table, proving each step; about 15 s.

    Raises ``AssertionError`` if a symbolic identity the derivation relies on fails.
    """
    T = frames()
    T06 = T[6]
    o5, o6 = T[5][:3, 3], T[6][:3, 3]
    R01 = T[1][:3, :3]
    J = sp.zeros(6, 6)
    J_wrist = sp.zeros(6, 6)
    for i in range(1, 7):
        z, o = T[i][:3, 2], T[i][:3, 3]
        J[:3, i - 1] = z.cross(o6 - o)
        J[3:, i - 1] = z
        J_wrist[:3, i - 1] = (R01.T * z).cross(R01.T * (o5 - o))
        J_wrist[3:, i - 1] = R01.T * z
    J = J.applyfunc(_tidy)
    J_wrist = J_wrist.applyfunc(_tidy)

    M = sp.zeros(6, 6)
    M[:3, :3] = R01
    M[:3, 3:] = -_cross_matrix(o6 - o5) * R01
    M[3:, 3:] = R01
    assert all(vanishes(entry, THETA) for entry in M * J_wrist - J), "J != M J_wrist"
    assert vanishes(M.det() - 1, THETA), "det M != 1"

    det_J = FACTORED_DET_J
    assert vanishes(J_wrist.det(method="berkowitz") - det_J, THETA), "det J is not the course's factored form"
    return Derivation(T06=T06, J=J, J_wrist=J_wrist, det_J=det_J)


def _source_fingerprint() -> str:
    """Changes whenever the derivation's code changes, so a stale cache is detected."""
    source = "".join(inspect.getsource(f) for f in (derive, frames, link_transform, _tidy, vanishes))
    source += repr(DH_TABLE)
    return hashlib.sha256(source.encode()).hexdigest()[:16]


def _to_json(derivation: Derivation) -> dict:
    return {
        "fingerprint": _source_fingerprint(),
        "sympy": sp.__version__,
        **{name: sp.srepr(getattr(derivation, name)) for name in ("T06", "J", "J_wrist", "det_J")},
    }


def write_cache(derivation: Derivation | None = None, path: Path = CACHE_PATH) -> Path:
    """Derive (unless given) and store the result as sympy ``srepr`` strings."""
    path.write_text(json.dumps(_to_json(derivation or derive()), indent=1) + "\n")
    return path


@functools.lru_cache(maxsize=1)
def load(path: Path = CACHE_PATH) -> Derivation:
    """The cached derivation (fast). Raises ``RuntimeError`` if the cache is stale or missing."""
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise RuntimeError(f"{path} is missing; run python -m ur10core.symbolic --write-cache") from None
    if data.get("fingerprint") != _source_fingerprint():
        raise RuntimeError(f"{path} is stale (the derivation changed); run python -m ur10core.symbolic --write-cache")
    parsed = {name: sp.sympify(data[name]) for name in ("T06", "J", "J_wrist", "det_J")}
    return Derivation(
        T06=sp.Matrix(parsed["T06"]), J=sp.Matrix(parsed["J"]), J_wrist=sp.Matrix(parsed["J_wrist"]),
        det_J=parsed["det_J"],
    )


def compact(expr):
    """Rewrite cos/sin of sums of joint angles in the course's shorthand: c2, c23, s234, ...

    The result uses symbols named ``c_23`` and so on, for display only.
    """
    replacements = {}
    for function, letter in ((sp.cos, "c"), (sp.sin, "s")):
        for node in sp.preorder_traversal(expr):
            if isinstance(node, function):
                argument = node.args[0]
                terms = argument.args if isinstance(argument, sp.Add) else (argument,)
                if all(term in THETA for term in terms):
                    index = "".join(sorted(str(THETA.index(term) + 1) for term in terms))
                    replacements[node] = sp.Symbol(f"{letter}_{index}")
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(lambda entry: entry.xreplace(replacements))
    return expr.xreplace(replacements)


def mathml(expr) -> str:
    """Presentation MathML of ``expr`` in the course's shorthand, inside ``<math display="block">``."""
    body = sp.printing.mathml(compact(expr), printer="presentation")
    return f'<math display="block">{body}</math>'


def det_j_latex() -> str:
    """``\\det J = a_{2} a_{3} (...)`` in LaTeX, from the cache."""
    return r"\det J = " + load().latex("det_J")


@functools.lru_cache(maxsize=1)
def det_j_mathml() -> str:
    """``det J = a2 a3 (a2 c2 + a3 c23 − d5 s234) s3 s5`` as block MathML, from the cache (printed once)."""
    body = sp.printing.mathml(compact(load().det_J), printer="presentation")
    return f'<math display="block"><mrow><mi>det</mi><mo>&#8289;</mo><mi>J</mi><mo>=</mo>{body}</mrow></math>'


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write-cache", action="store_true", help=f"derive and write {CACHE_PATH.name}")
    args = parser.parse_args(argv)
    if args.write_cache:
        print(f"wrote {write_cache()}")
    else:
        derivation = load()
        print("det J =", derivation.det_J)


if __name__ == "__main__":
    main()
