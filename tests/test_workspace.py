"""The workspace cloud: positions by FK, manipulability = |det J|, reproducible."""

import numpy as np
import pytest


def test_points_and_manipulability_come_from_fk_and_the_jacobian(course):
    points, manipulability, q = course.sample_workspace(20000, seed=3, return_joints=True)
    assert points.shape == (20000, 3) and manipulability.shape == (20000,) and q.shape == (20000, 6)
    np.testing.assert_allclose(points, course.fk(q)[:, :3, 3], atol=1e-14)
    np.testing.assert_allclose(manipulability, np.abs(np.linalg.det(course.jacobian(q))), atol=1e-14)
    assert (q[:, :5] > -np.pi).all() and (q[:, :5] <= np.pi).all() and (q[:, 5] == 0).all()


def test_reproducible_and_seeded(course):
    a, ma = course.sample_workspace(150_000, seed=7)  # more than one block: threaded
    b, mb = course.sample_workspace(150_000, seed=7)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(ma, mb)
    c, _ = course.sample_workspace(150_000, seed=8)
    assert not np.array_equal(a, c)
    # a prefix of a larger cloud is the smaller cloud: blocks are seeded by position
    d, _ = course.sample_workspace(70_000, seed=7)
    np.testing.assert_array_equal(d[:65536], a[:65536])


def test_inside_the_reach_sphere(course):
    points, _ = course.sample_workspace(100_000)
    shoulder = np.array([0, 0, course.d1])
    reach = np.sqrt((course.a2 + course.a3) ** 2 + course.d4**2) + course.d5 + course.d6
    assert np.linalg.norm(points - shoulder, axis=-1).max() <= reach
    # docs/kinematics.md §1: roughly a sphere of Ø2600 mm around the base
    assert np.linalg.norm(points - shoulder, axis=-1).max() == pytest.approx(1.3, abs=0.1)


def test_uniform_joint_angles(course):
    _, _, q = course.sample_workspace(200_000, seed=1, return_joints=True)
    counts, _ = np.histogram(q[:, 2], bins=10, range=(-np.pi, np.pi))
    assert counts.min() > 0.9 * 20_000 and counts.max() < 1.1 * 20_000


def test_lowest_points_is_the_lowest_of_every_body_point_moved_in_full(course):
    from ur10core.workspace import lowest_points

    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    frames = course.frames(q)  # (50, 7, 4, 4)
    points = rng.normal(scale=0.1, size=(7, 12, 3))
    lowest = lowest_points(frames, points)
    moved = np.einsum("nlij,lpj->nlpi", frames[..., :3, :3], points) + frames[:, :, None, :3, 3]
    flat = moved.reshape(50, -1, 3)
    expected = flat[np.arange(50), np.argmin(flat[..., 2], axis=1)]
    np.testing.assert_allclose(lowest, expected, atol=1e-12)
    np.testing.assert_allclose(lowest_points(frames[7], points), expected[7], atol=1e-12)  # one arm
    with pytest.raises(ValueError, match="body_points"):
        lowest_points(frames, points[:6])


def test_a_horizontal_section_is_sampled_in_its_plane(course):
    points, manipulability, q = course.sample_horizontal_section(0.6, 5000, seed=1, return_joints=True)
    assert (points[:, 2] == 0.6).all()
    np.testing.assert_allclose(course.fk(q)[:, :3, 3], points, atol=1e-12)
    np.testing.assert_allclose(manipulability, np.abs(np.linalg.det(course.jacobian(q))), atol=1e-12)
    assert (q[:, :5] > -np.pi).all() and (q[:, :5] <= np.pi).all() and (q[:, 5] == 0).all()
    again, _ = course.sample_horizontal_section(0.6, 5000, seed=1)
    np.testing.assert_array_equal(points, again)


def test_a_horizontal_section_covers_what_a_slab_of_the_cloud_covers(course):
    """The same ring of radii as the points of a big cloud within 5 mm of the plane, and far more of them."""
    cloud, _ = course.sample_workspace(1_000_000, seed=2)
    slab = cloud[np.abs(cloud[:, 2] - 0.6) < 0.005]
    section, _ = course.sample_horizontal_section(0.6, 20000, seed=2)
    r_slab, r_section = np.hypot(*slab[:, :2].T), np.hypot(*section[:, :2].T)
    assert len(slab) < 5000 < len(section)
    assert abs(r_slab.min() - r_section.min()) < 0.03 and abs(r_slab.max() - r_section.max()) < 0.03
    # and the radii in between are all filled: no ring of the slab is missing from the section
    bins = np.linspace(r_slab.min(), r_slab.max(), 30)
    slab_hist, _ = np.histogram(r_slab, bins)
    section_hist, _ = np.histogram(r_section, bins)
    assert (section_hist[slab_hist > 5] > 0).all()


def test_a_section_nobody_reaches_is_refused(course):
    with pytest.raises(ValueError, match="outside the workspace"):
        course.sample_horizontal_section(2.0, 10)
    with pytest.raises(ValueError, match="outside the workspace"):
        course.sample_horizontal_section(float("nan"), 10)
    with pytest.raises(ValueError, match="positive integer"):
        course.sample_horizontal_section(0.5, 0)
