"""The sympy derivation: cached result equals a fresh derivation; it agrees with the numbers."""

import xml.dom.minidom

import numpy as np
import pytest
import sympy as sp

from ur10core import symbolic
from ur10core.symbolic import LENGTHS, THETA

from .conftest import random_joints

pytestmark = pytest.mark.core


@pytest.fixture(scope="module")
def cached():
    return symbolic.load()


def _numeric(expr, arm):
    f = sp.lambdify(THETA + LENGTHS, expr, "numpy")
    return lambda q: np.array(f(*q, *arm.dh_lengths), dtype=float)


@pytest.mark.slow
def test_cache_equals_a_fresh_derivation(cached):
    fresh = symbolic.derive()  # ~15 s; also proves J = M J_wrist, det M = 1, det J factored
    for name in ("T06", "J", "J_wrist"):
        a, b = getattr(fresh, name), getattr(cached, name)
        # the cache is the derivation's srepr: identical unless sympy changed how it writes a term
        assert a == b or (a - b).applyfunc(sp.simplify) == sp.zeros(*a.shape), name
    assert fresh.det_J == cached.det_J or sp.simplify(fresh.det_J - cached.det_J) == 0


def test_the_proof_of_the_factored_form_fails_on_a_wrong_one(cached):
    """derive() proves det J_wrist = the course's factors with :func:`symbolic.vanishes`; a wrong factor is caught."""
    det = cached.J_wrist.det(method="berkowitz")
    assert symbolic.vanishes(det - symbolic.FACTORED_DET_J, THETA)
    d5 = LENGTHS[4]
    wrong_sign = symbolic.FACTORED_DET_J.subs(d5, -d5)
    assert not symbolic.vanishes(det - wrong_sign, THETA)
    assert not symbolic.vanishes(det - symbolic.FACTORED_DET_J.subs(sp.sin(THETA[2]), sp.cos(THETA[2])), THETA)


def test_det_j_is_the_factored_form(cached):
    assert sp.simplify(cached.det_J - symbolic.FACTORED_DET_J) == 0
    assert cached.det_J == symbolic.FACTORED_DET_J.factor() or sp.factor(cached.det_J) == cached.det_J


def test_t06_matches_course_closed_form(cached):
    c = {j: sp.cos(THETA[j - 1]) for j in range(1, 7)}
    s = {j: sp.sin(THETA[j - 1]) for j in range(1, 7)}
    c23, s23 = sp.cos(THETA[1] + THETA[2]), sp.sin(THETA[1] + THETA[2])
    c234, s234 = sp.cos(sum(THETA[1:4])), sp.sin(sum(THETA[1:4]))
    d1, a2, a3, d4, d5, d6 = LENGTHS
    course = sp.Matrix(  # docs/kinematics.md §3, typed from the notes
        [
            [c[6] * (-s[1] * s[5] + c[1] * c[5] * c234) - s[6] * s234 * c[1], -s[6] * (-s[1] * s[5] + c[1] * c[5] * c234) - s234 * c[1] * c[6], s[1] * c[5] + s[5] * c[1] * c234,
             c[1] * (a2 * c[2] + a3 * c23) + d4 * s[1] - d5 * s234 * c[1] + d6 * (s[1] * c[5] + s[5] * c[1] * c234)],
            [c[6] * (s[5] * c[1] + s[1] * c[5] * c234) - s[6] * s234 * s[1], -s[6] * (c[1] * s[5] + s[1] * c[5] * c234) - s234 * s[1] * c[6], -c[1] * c[5] + s[5] * s[1] * c234,
             s[1] * (a2 * c[2] + a3 * c23) - d4 * c[1] - d5 * s234 * s[1] - d6 * (c[1] * c[5] - s[5] * s[1] * c234)],
            [s[6] * c234 + s234 * c[5] * c[6], c[6] * c234 - s234 * c[5] * s[6], s[5] * s234, a2 * s[2] + a3 * s23 + d1 + d5 * c234 + d6 * s[5] * s234],
            [0, 0, 0, 1],
        ]
    )
    difference = (cached.T06 - course).applyfunc(lambda e: sp.simplify(sp.expand_trig(e)))
    assert difference == sp.zeros(4, 4)


def test_symbolic_matches_numeric_core(cached, any_arm):
    q = random_joints(50, seed=60)
    T06, J, det_J = (_numeric(e, any_arm) for e in (cached.T06, cached.J, cached.det_J))
    for k in range(len(q)):
        np.testing.assert_allclose(T06(q[k]), any_arm.fk(q[k]), atol=1e-14)
        np.testing.assert_allclose(J(q[k]), any_arm.jacobian(q[k]), atol=1e-14)
        assert float(det_J(q[k])) == pytest.approx(np.linalg.det(any_arm.jacobian(q[k])), rel=1e-9, abs=1e-15)


def test_display_strings(cached):
    latex = symbolic.det_j_latex()
    assert latex.startswith(r"\det J = ") and "c_{23}" in latex and "s_{234}" in latex
    mathml = symbolic.det_j_mathml()
    dom = xml.dom.minidom.parseString(mathml.replace("&InvisibleTimes;", "&#8290;"))
    text = "".join(node.data for node in _text_nodes(dom))
    assert "det" in text and "234" in text and "23" in text
    assert cached.latex("T06").startswith(r"\left[")
    assert symbolic.mathml(cached.T06).startswith('<math display="block">')


def _text_nodes(node):
    for child in node.childNodes:
        if child.nodeType == child.TEXT_NODE:
            yield child
        else:
            yield from _text_nodes(child)


def test_stale_cache_is_refused(tmp_path):
    stale = tmp_path / "cache.json"
    stale.write_text('{"fingerprint": "old", "T06": "", "J": "", "J_wrist": "", "det_J": ""}')
    with pytest.raises(RuntimeError, match="stale"):
        symbolic.load.__wrapped__(stale)
    with pytest.raises(RuntimeError, match="missing"):
        symbolic.load.__wrapped__(tmp_path / "nothing.json")
