"""det J of the course's other arms: the cached sympy derivation against a fresh one and against numbers."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from ur10core import symbolic_arms
from ur10core import Arm
from ur10core.serial import PRESETS

pytestmark = pytest.mark.core

#: The rows of J [v; ω] whose square determinant is det J, per task (docs/kinematics.md §7.6).
SQUARE_ROWS = {"kr210": slice(0, 6), "elbow": slice(0, 6), "stanford": slice(0, 6), "scara": [0, 1, 2, 5],
               "planar_elbow": [0, 1], "cylindrical": [0, 1, 2], "cylindrical_wrist": slice(0, 6)}


@pytest.mark.slow
def test_cache_matches_a_fresh_derivation():
    """~10 s: derives every arm again, proving det J = constant × factors symbolically."""
    for name in PRESETS:
        fresh, cached = symbolic_arms.derive(name), symbolic_arms.load(name)
        assert fresh.constant == cached.constant
        assert [f.name for f in fresh.factors] == [f.name for f in cached.factors]
        assert all(sp.simplify(a.expression - b.expression) == 0 for a, b in zip(fresh.factors, cached.factors))


@pytest.mark.parametrize("name", PRESETS)
def test_factors_multiply_to_the_numeric_det_j(name):
    arm = Arm.preset(name)
    derivation = symbolic_arms.load(name)
    q = np.random.default_rng(2).uniform(arm.limits[:, 0], arm.limits[:, 1], (200, arm.n_joints))
    J = arm.jacobian(q)[:, SQUARE_ROWS[name], :]
    numeric = np.linalg.det(J)
    factors = arm.singularity_factors(q)
    assert factors.shape == (200, len(derivation.factors))
    np.testing.assert_allclose(float(derivation.constant) * factors.prod(axis=-1), numeric, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.abs(numeric), arm.manipulability(q), rtol=1e-9, atol=1e-12)


def test_each_factor_is_the_geometry_it_names():
    kr210 = Arm.preset("kr210")
    q = np.random.default_rng(3).uniform(-2, 2, (100, 6))
    shoulder, elbow, wrist = kr210.singularity_factors(q).T
    frames = kr210.frames(q)
    centre = frames[:, kr210.solver.wrist.first_row + 1, :3, 3]
    np.testing.assert_allclose(np.abs(shoulder), np.hypot(centre[:, 0], centre[:, 1]), atol=1e-12)  # WC from axis 1
    np.testing.assert_allclose(wrist, np.sin(q[:, 4]), atol=1e-15)
    # the elbow factor vanishes where the closed form's upper arm and forearm are in line
    plane = kr210.solver.plane
    stretched = q.copy()
    stretched[:, 2] = (0.0 - plane["phi"]) * plane["s3"]
    assert np.abs(kr210.singularity_factors(stretched)[:, 1]).max() < 1e-12
    assert np.abs(kr210.singularity_factors(q)[:, 1]).min() > 1e-6
    meanings = [f.meaning for f in symbolic_arms.load("stanford").factors]
    assert "d3 = 0" in meanings[0] and "θ5 = 0" in meanings[2]


def test_custom_arms_report_the_smallest_singular_value_instead():
    arm = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR")
    with pytest.raises(ValueError, match="smallest_singular_value"):
        arm.singularity_factors([0.1, 0.2])
    assert arm.smallest_singular_value([0.1, 0.0]) < 1e-12 < arm.smallest_singular_value([0.1, 0.5])


def test_a_stale_cache_is_refused(tmp_path):
    stale = tmp_path / "stale.json"
    stale.write_text('{"fingerprint": "0", "arms": {}}')
    with pytest.raises(RuntimeError, match="stale"):
        symbolic_arms._cache.__wrapped__(stale)


#: Every arm but the UR family's places itself on a singularity by search (``Arm.singular_configuration``).
SEARCHED = (*PRESETS, "three_dof")


@pytest.mark.parametrize("name", SEARCHED)
def test_every_arm_is_put_on_each_of_its_singularities_within_its_limits(name):
    """The pose found is singular by the DH Jacobian's own smallest singular value (not the factors it was
    searched with), inside the limits, with one or two joints changed; the cylindrical arms' stroke keeps
    them off their reach singularity, and they say so."""
    arm = Arm.preset(name)
    starts = arm.sample_joints(20, seed=11)
    for kind in arm.factor_names:
        if name.startswith("cylindrical") and kind == "reach":
            with pytest.raises(ValueError, match=r"reach singularity \(d3 = 0: the (tool|wrist centre) on the column.s axis"):
                arm.singular_configuration(kind, starts[0])
            continue
        found = arm.singular_configuration(kind, starts)
        assert found.shape == starts.shape
        assert arm.within_limits(found).all()
        assert (arm.smallest_singular_value(found) < 1e-12).all(), kind
        assert np.median(arm.smallest_singular_value(starts)) > 1e-2
        changed = (np.abs(found - starts) > 1e-12).sum(axis=-1)
        assert set(changed.tolist()) <= {1, 2}, kind
    with pytest.raises(ValueError, match="no 'knee' singularity"):
        arm.singular_configuration("knee", starts[0])


@pytest.mark.parametrize("name, kind, start, expected", [
    ("stanford", "wrist", [30, 60, 0.3, 20, 40, 10], [30, 60, 0.3, 20, 0, 10]),  # θ5 = 0
    ("stanford", "stroke", [30, 60, 0.3, 20, 40, 10], [30, 60, 0.0, 20, 40, 10]),  # d3 = 0: a double zero, d3²
    ("scara", "elbow", [30, 120, 0.1, 20], [30, 0, 0.1, 20]),  # θ2 = 180° is past its 157.5° stop: 0°, the zero in range
    ("scara", "elbow", [30, -50, 0.1, 20], [30, 0, 0.1, 20]),
    ("planar_elbow", "elbow", [30, 150], [30, 180]),  # folded, nearer than stretched
    ("kr210", "elbow", [0, 15, -30, 20, 40, 10], [0, 15, -92.0618, 20, 40, 10]),  # 1.5 c3 = 0.054 s3
])
def test_the_searched_singularity_is_the_nearest_by_one_joint(name, kind, start, expected):
    """Closed forms (docs/kinematics.md §7.6): the one joint its factor names, to the nearest zero in range."""
    arm = Arm.preset(name)
    to_joint = lambda values: np.where(arm.revolute, np.radians(values), values)  # noqa: E731
    found = arm.singular_configuration(kind, to_joint(start))
    shown = np.where(arm.revolute, np.degrees(found), found)
    np.testing.assert_allclose(shown, expected, atol=1e-4)


def test_each_factors_meaning_reads_as_a_clause_after_zero_when():
    """The gauges write "zero when {meaning}": "zero when the wrist centre on axis 1" lacked its verb (KR210, elbow
    arm). Each meaning's condition, before its colon, is an equation or has its verb."""
    from ur10core.symbolic_arms import MEANINGS

    for name, factors in MEANINGS.items():
        for factor, meaning in factors:
            condition = meaning.split(":")[0]
            assert "=" in condition or " is " in condition or " are " in condition, (name, factor, meaning)
