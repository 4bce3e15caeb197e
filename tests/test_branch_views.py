"""What the ghost arms show: numbers, coinciding branches, the focus choices, the floor check."""

from __future__ import annotations

import numpy as np
import pytest

from ur10teach.features.ik_target import (ALL_BRANCHES, branch_labels, branch_table, flipped, focus_options, focused,
                                          same_pose_groups, status_markdown)
from ur10teach.meshes import body_points, load_links
from ur10teach.state import ArmState
from ur10core import SLOTS, Arm


@pytest.fixture(scope="module")
def points():
    return body_points(load_links("course"))


def state(course, degrees, points) -> ArmState:
    return ArmState(course, np.radians(degrees), body_points=points)


def test_flipping_a_choice_changes_that_choice_alone():
    for slot in SLOTS:
        for choice in ("shoulder", "elbow", "wrist"):
            other = SLOTS[flipped(slot.index, choice)]
            for name in ("shoulder", "elbow", "wrist"):
                assert (getattr(other, name) != getattr(slot, name)) == (name == choice)


def test_focus_choices(course):
    assert focused(ALL_BRANCHES, 4, course).all()
    for k in range(8):
        assert focused(f"Only branch {k + 1}", 4, course).nonzero()[0].tolist() == [k]
    assert set(focused("Flip the wrist", 4, course).nonzero()[0]) == {4, flipped(4, "wrist")}
    assert set(focused("Flip the shoulder", -1, course).nonzero()[0]) == {0, flipped(0, "shoulder")}  # out of reach
    assert len(focus_options(course)) == 12
    with pytest.raises(ValueError, match="ghosts shown"):
        focused("Only branch 9x", 4, course)
    # an arm whose slots are not the UR family's shoulder, elbow and wrist choices: one branch, or all
    scara = Arm.preset("scara")
    assert focus_options(scara) == (ALL_BRANCHES, "Only branch 1", "Only branch 2")
    with pytest.raises(ValueError, match="ghosts shown"):
        focused("Flip the wrist", 0, scara)


def test_every_branch_is_numbered_where_none_coincide(course, points):
    snapshot = state(course, [30, 45, 26, 50, 60, 80], points).last
    groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
    assert groups == tuple((k,) for k in range(8))
    assert branch_labels(snapshot, groups) == ["1", "2", "3", "4", "arm: 5", "6", "7", "8"]


def test_coinciding_branches_share_one_label(course, points):
    """At the zero pose (elbow stretched, wrist singular) the branches that meet are drawn and named as one."""
    snapshot = state(course, [0, 0, 0, 0, 0, 0], points).last
    groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
    for group in groups:  # an independent check of "coincide": the frames themselves, from FK of each branch
        frames = course.frames(snapshot.solution.q[list(group)])[:, :, :3, 3]
        assert np.abs(frames - frames[0]).max() < 1e-3
    assert sorted(k for g in groups for k in g) == snapshot.solution.valid.nonzero()[0].tolist()
    labels = branch_labels(snapshot, groups)
    arm_group = next(g for g in groups if snapshot.slot in g)
    assert labels[arm_group[0]] == "arm: " + " = ".join(str(k + 1) for k in arm_group)
    assert len(arm_group) > 1


@pytest.mark.parametrize("name, kind", [("elbow", "elbow"), ("stanford", "stroke"), ("stanford", "shoulder")])
def test_every_branch_in_one_pose_is_named_all_of_them(name, kind):
    """Stretched, the elbow arm's eight branches share every joint (the shoulder's two sides too, along one line);
    so do the Stanford arm's with the wrist centre on its shoulder or on axis 1. "arm: 1 = 2 = 3 = 4 = 5 = 6 = 7 = 8"
    was too wide for a free spot in lecture mode and sat over the DH frames' "z2" (CI, 2026-12-04): it is "arm: all 8"."""
    snapshot = ArmState(Arm.preset(name)).place_in_singularity(kind)
    groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
    assert groups == (tuple(range(8)),)
    frames = Arm.preset(name).frames(snapshot.solution.q)[:, :, :3, 3]  # independently: every branch's joints, by FK
    assert np.abs(frames - frames[0]).max() < 1e-3
    assert branch_labels(snapshot, groups) == ["arm: all 8"] + [""] * 7


@pytest.mark.parametrize("name", ["stanford", "kr210", "elbow", "cylindrical", "cylindrical_wrist", "three_dof",
                                  "scara", "planar_elbow", "course"])
def test_the_status_says_which_ghosts_lie_on_each_other_though_their_joints_differ(name):
    """On an arm with a spherical wrist, a flipped wrist moves no joint: its ghost lies on the other's at every
    pose, labelled "1 = 2". Until 2026-12-04 nothing said so, while the table beside it gave the two different
    joints (and docs said ghosts are merged at a singularity): the status line now names such ghosts."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(4)
    low, high = np.clip(arm.limits.T, -np.pi, np.pi)
    snapshot = ArmState(arm, rng.uniform(0.8 * low + 0.2 * high, 0.2 * low + 0.8 * high)).last  # off any singularity
    groups = [g for g in same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid) if len(g) > 1]
    status = status_markdown(snapshot)
    for group in groups:  # independently: each branch's joints by FK, and its joint values
        q = snapshot.solution.q[list(group)]
        frames = arm.frames(q)[:, :, :3, 3]
        assert np.abs(frames - frames[0]).max() < 1e-6
        assert np.abs(np.angle(np.exp(1j * (q - q[0])))).max() > 0.1  # (a prismatic joint's m read as radians)
        assert " = ".join(str(k + 1) for k in group) in status.split("lie on each other")[0]
    assert ("lie on each other" in status) == bool(groups) == (name not in ("scara", "planar_elbow", "course"))


@pytest.mark.parametrize("name", ["stanford", "elbow", "scara", "cylindrical", "three_dof", "course"])
def test_the_status_counts_the_branches_a_class_challenge_counts(name):
    """*SCARA: one branch only* and every branch-count task count the branches within the joint limits, as the reach
    map does; the status line counted every branch that reaches, beyond a limit or not (the Stanford arm's "8 of 8"
    where 4 need d3 < 0), so a student could read "2 of 2" on a target the server counted as one (until 2026-12-04)."""
    import re

    from ur10core.challenges import _count

    arm = Arm.preset(name)
    on_a_limit = arm.sample_joints(2 * arm.n_joints, seed=6)  # each joint on each end (the desktop arm's θ3 = 0, 180°)
    on_a_limit[np.arange(2 * arm.n_joints), np.tile(np.arange(arm.n_joints), 2)] = arm.limits.T.reshape(-1)
    for q in [*arm.sample_joints(25, seed=5), *on_a_limit]:
        snapshot = ArmState(arm, q).last
        counted = int(re.match(r"\*\*(\d+) of \d+ branches\*\*", status_markdown(snapshot)).group(1))
        assert counted == _count(arm, snapshot.target), status_markdown(snapshot)
        assert counted >= 1, status_markdown(snapshot)  # the arm is there: a branch within the limits reaches it


def test_an_arm_through_the_floor_is_marked(course, points):
    down = state(course, [0, -90, 0, -90, 0, 0], points).last  # the arm hangs below its base
    assert down.through_floor[0] and down.lowest[0, 2] < -0.5
    up = state(course, [30, 45, 26, 50, 60, 80], points).last
    assert not up.through_floor.any()
    groups = same_pose_groups(down.ghost_frames, down.solution.valid)
    assert all(text.endswith("⚠ floor") for text in branch_labels(down, groups) if text)
    assert "through the floor" in branch_table(down)
    assert "through the floor" not in branch_table(up)


def test_the_floor_check_sees_the_bodies_not_just_the_joints(course, points):
    """The lowest joint 2 cm above the floor: every frame origin is above it, the arm's body is not."""
    low, high = -np.pi / 2, 0.0  # tip the shoulder down from the zero pose until the lowest joint is 2 cm up
    for _ in range(60):
        middle = (low + high) / 2
        low, high = (low, middle) if course.frames([0, middle, 0, 0, 0, 0])[1:, 2, 3].min() > 0.02 else (middle, high)
    q = [0, high, 0, 0, 0, 0]
    np.testing.assert_allclose(course.frames(q)[1:, 2, 3].min(), 0.02, atol=1e-6)
    assert course.frames(q)[:, 2, 3].min() > -1e-9
    assert not ArmState(course, q).last.through_floor[0]  # the frame origins alone
    assert ArmState(course, q, body_points=points).last.through_floor[0]


@pytest.mark.parametrize("legend", ["hull", "cloud", "map 1", "map 2", "map 4", "map 8"])
def test_every_legend_drawn_in_3d_fits_a_projectors_canvas_in_lecture_mode(legend):
    """The cloud's, the hull's and the branch-count map's legends were one line each, of 70 to 110 characters:
    in lecture mode (an em of 24 px) 1,100 to 1,600 px wide, off the side of the smallest canvas a class looks
    at. Each now comes in lines that fit it."""
    from ur10teach.features import reach_map, workspace
    from ur10teach.features.branch_labels import DEFAULT_VIEW, label_size
    from ur10teach.style import NAME_SCALE, label_scale

    text = {"hull": workspace.HULL_LEGEND, "cloud": workspace.legend_text(0.123)}.get(legend)
    if text is None:
        text = reach_map.legend_text(int(legend.split()[1]))
    scale = 1.3 if legend in ("hull", "cloud") else NAME_SCALE  # the map's is placed with the names at the tool
    width, _ = label_size(text, label_scale(scale, lecture=True))
    assert width <= 0.9 * DEFAULT_VIEW.width, (text, width)


def test_a_long_label_near_the_canvas_edge_is_drawn_whole_on_it_and_first():
    """The map's legend, placed with the names at the tool, stands on the top of the map, often at the canvas's top
    edge and beside the cloud's legend (2026-12-05, the desktop arm in lecture mode). Only spots whole on the canvas
    are taken, and the spots are label heights apart in both directions at once: a 650 px wide legend near the
    edge had one, over the cloud's legend, and was drawn there. It is now first pulled onto the canvas. It is also
    placed before the one-line names: taken first by a name beside it, its only free spot sent it half a screen
    away."""
    from ur10teach.features.branch_labels import ScreenView, boxes, overlapping, place

    view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), height=720.0, width=736.0)
    legend = "branches reaching each point:\nyellow 1 · green 2 · teal 3 · purple 4"
    scale = 2.24

    def box(point, text, anchor="bottom-center"):
        return boxes(view.to_screen(np.array([point], dtype=float))[0], [text], scale, anchor)[0]

    def at(pixel):  # the point in the plane y = 0 drawn at (x, y) px from the canvas's centre
        per_px = 2 * np.tan(view.fov / 2) * 3.0 / view.height
        return np.array([pixel[0] * per_px, 0.0, pixel[1] * per_px])

    top = at((70.0, 330.0))  # its box would stand over the top and right edges
    cloud = (at((65.0, 240.0)), "colour = manipulability |det J|:\ndark violet 0 (singular) … yellow ≥ 3.433", scale,
             "bottom-center")
    name = at((-200.0, 250.0))  # a name under where the legend would come, left of it
    placed = place(np.array([top, name]), [legend, "velocity"], view, scale, fixed=[cloud])
    drawn = {text: box(position, text) for _, text, position, _ in placed}
    canvas = np.array([-view.width / 2, -view.height / 2, view.width / 2, view.height / 2])
    for text, b in drawn.items():
        assert (b[:2] >= canvas[:2] - 1e-6).all() and (b[2:] <= canvas[2:] + 1e-6).all(), (text, b)
        assert not overlapping(b, box(*cloud[:2], cloud[3]), gap=0.0), text
    assert not overlapping(drawn[legend], drawn["velocity"], gap=0.0)
    # right under the cloud's legend: the name moved, not the legend
    assert box(*cloud[:2], cloud[3])[1] - drawn[legend][3] < 2 * (drawn[legend][3] - drawn[legend][1])
    # a canvas narrower than the legend (lecture mode's wide panel beside a 1280 px window): centred on it, and
    # still clear of the cloud's legend (until then no spot was whole on the canvas, and it stayed over it)
    view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), height=630.0, width=600.0)
    top, cloud = at((0.0, 300.0)), (at((0.0, 200.0)), *cloud[1:])
    (_, _, position, _), = place(np.array([top]), [legend], view, scale, fixed=[cloud])
    b = box(position, legend)
    assert b[0] == pytest.approx(-b[2]) and b[2] > view.width / 2 and -view.height / 2 <= b[1] < b[3] <= view.height / 2
    assert not overlapping(b, box(*cloud[:2], cloud[3]), gap=0.0)


def test_a_crowd_of_names_at_one_spot_is_read_whole_on_the_projectors_canvas():
    """A class's tools on the target of a reach challenge are one spot on the projector, and their names one label.
    Until 2026-12-07 it was one line: twelve students' names in lecture mode ran off both sides of the canvas
    (1280 px window, the panel beside it), and thirty would have been 3,000 px wide. It now comes in lines that
    fit the canvas, every name whole, in the order they stand on the screen; a lecture hall's hundred would have
    covered the canvas: as many lines as fill half of it are shown, and how many more there are."""
    from ur10teach.features.branch_labels import JOIN, ScreenView, boxes, place
    from ur10teach.style import NAME_SCALE, label_scale

    view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), height=720.0, width=736.0)
    scale = label_scale(NAME_SCALE, lecture=True)
    names = [f"{'✓ ' if k % 3 == 0 else ''}student {k + 1}" for k in range(30)]
    target = np.array([0.1, 0.0, -0.2])
    tools = target + np.linspace(0.0, 1e-4, len(names))[:, None] * [1.0, 0.0, 0.0]  # left to right, within a pixel
    (members, text, position, point), = place(tools, names, view, scale)
    assert members == tuple(range(len(names))) and np.allclose(point, tools.mean(axis=0))
    lines = text.split("\n")
    assert [name for line in lines for name in line.split(JOIN)] == names and len(lines) > 1
    box = boxes(view.to_screen(position[None])[0], [text], scale)[0]
    assert -view.width / 2 <= box[0] < box[2] <= view.width / 2 and -view.height / 2 <= box[1] < box[3] <= view.height / 2
    # a few names, or the branch numbers, stay one line
    (_, few, _, _), = place(tools[:3], names[:3], view, scale)
    assert few == JOIN.join(names[:3])
    # a lecture hall's hundred: as many lines as half the canvas holds, then how many more there are
    hall = [f"student {k + 1}" for k in range(100)]
    crowd = target + np.linspace(0.0, 1e-4, len(hall))[:, None] * [1.0, 0.0, 0.0]
    (_, text, position, _), = place(crowd, hall, view, scale)
    *lines, more = text.split("\n")
    shown = [name for line in lines for name in line.split(JOIN)]
    assert shown == hall[:len(shown)] and more == f"… and {len(hall) - len(shown)} more" and len(shown) >= 20
    box = boxes(view.to_screen(position[None])[0], [text], scale)[0]
    assert box[3] - box[1] <= view.height / 2 and -view.width / 2 <= box[0] < box[2] <= view.width / 2


def test_on_a_phone_held_upright_labels_are_placed_above_the_panel():
    """A phone held upright shows the panel over the lower 60 % of its canvas, and frames the arm above it; the
    labels were placed on the whole canvas, and those a crowd pushed down went under the panel (the UR10's "arm: 5"
    and "7" by its wrist singularity, 2026-12-07). They are placed in the band above it, apart: when none of the
    spots around a label's point is free there, at the nearest free one in the band."""
    from ur10teach.features.branch_labels import ScreenView, boxes, overlapping, place
    from ur10teach.features.camera import SHEET_UNCOVERED

    view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), height=664.0, width=390.0,
                      covered=1.0 - SHEET_UNCOVERED)
    per_px = 2 * np.tan(view.fov / 2) * 3.0 / view.height
    band = view.height / 2 - SHEET_UNCOVERED * view.height  # the panel's top edge, px from the canvas's centre
    texts = [f"{k + 1} ⚠ floor" for k in range(8)]
    for seed in range(20):  # eight elbows in the band's lower half, as a crowd by a singularity
        rng = np.random.default_rng(seed)
        pixels = np.column_stack([rng.uniform(-100.0, 100.0, 8), rng.uniform(band + 10.0, band + 150.0, 8)])
        points = np.column_stack([pixels[:, 0] * per_px, np.zeros(8), pixels[:, 1] * per_px])
        placed = place(points, texts, view, 1.6, merge_px=0.0)
        drawn = [boxes(view.to_screen(position[None])[0], [text], 1.6)[0] for _, text, position, _ in placed]
        assert len(drawn) == 8
        for k, box in enumerate(drawn):
            assert box[1] >= band - 1e-6 and box[3] <= view.height / 2 + 1e-6 and abs(box[0]) <= view.width / 2, (seed, box)
            assert not any(overlapping(box, other, gap=0.0) for other in drawn[k + 1:]), seed


def test_labels_are_placed_on_any_canvas_whatever_their_points_and_sizes():
    """Placing never fails: a label wider or taller than the canvas, its point off the canvas or behind the camera, a
    phone's band, crowds (a grid search over the canvas once raised on a label with no spot on it)."""
    from ur10teach.features.branch_labels import ScreenView, place

    rng = np.random.default_rng(11)
    for _ in range(300):
        view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0), height=float(rng.uniform(80, 900)),
                          width=float(rng.uniform(80, 1400)), covered=float(rng.choice([0.0, 0.6])))
        count = int(rng.integers(1, 12))
        points = rng.normal(0.0, 1.5, (count, 3)) + [0.0, rng.choice([0.0, -4.0]), 0.0]  # some behind the camera
        texts = ["x" * int(rng.integers(0, 90)) + "\nline" * int(rng.integers(0, 3)) for _ in range(count)]
        placed = place(points, texts, view, float(rng.uniform(1.0, 3.0)))
        assert sorted(k for members, *_ in placed for k in members) == [k for k, text in enumerate(texts) if text]
        assert all(np.isfinite(position).all() for _, _, position, _ in placed)


@pytest.mark.parametrize("nickname", ["王小明同学", "さくら先生", "김민준", "😀😀😀", "Ｒｏｂｏｔ"])
def test_a_nickname_in_wide_characters_is_measured_whole(nickname):
    """A CJK character, a full-width letter or an emoji takes a whole em (its font's advance), not the 0.62 em of
    a Latin one that every character was measured at until 2026-12-07: a Chinese nickname's label was taken
    for 2/3 of its width, and the placing let it overlap its neighbours on the projector."""
    from ur10teach.features.branch_labels import EM_PX, label_size

    for scale in (1.0, 2.56):
        width, _ = label_size(nickname, scale)
        assert width >= EM_PX * scale * len(nickname)
        assert label_size(f"✓ {nickname}\nab", scale)[0] > width  # the longest line counts


@pytest.mark.parametrize("name", ["stanford", "elbow", "three_dof"])
def test_a_ghost_the_arm_cannot_be_put_on_reads_limit_and_one_it_can_does_not(name):
    """Half a Stanford arm's branches need d3 < 0: their ghosts looked like the others, and a click on one was
    refused. A group of coinciding branches all beyond a limit is labelled "⚠ limit", on its lead slot; one with
    a branch within the limits carries its label on that branch, the one a click takes."""
    arm = Arm.preset(name)
    seen_beyond = seen_mixed = 0
    for q in arm.sample_joints(60, seed=7):
        snapshot = ArmState(arm, q).last
        within = snapshot.solution.within_limits
        groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
        labels = branch_labels(snapshot, groups)
        for group in groups:
            carrier = [k for k in group if labels[k]]
            assert len(carrier) == 1
            assert ("⚠ limit" in labels[carrier[0]]) == (not within[list(group)].any())
            assert within[carrier[0]] == within[list(group)].any()  # a click on the ghost takes a branch it can
            seen_beyond += not within[list(group)].any()
            seen_mixed += bool(within[list(group)].any() and not within[list(group)].all())
    assert seen_beyond and seen_mixed  # both cases were met


@pytest.mark.parametrize("name", ["stanford", "elbow"])
def test_only_branch_k_draws_and_numbers_k_where_another_lies_on_it(name):
    """A flipped wrist moves no joint: branches 1 and 5 are one ghost. With *Ghosts shown: Only branch 5* the ghost
    drawn (and so clicked) is 5's and its number's line has 5's colour, not 1's, which a click would have taken."""
    from types import SimpleNamespace

    from ur10teach.features.course_arms.scene import LineDrawing
    from ur10teach.features.ik_target import numbered

    arm = Arm.preset(name)
    for q in arm.sample_joints(100, seed=8):
        snapshot = ArmState(arm, q).last
        within = snapshot.solution.within_limits
        pairs = [g for g in same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
                 if snapshot.slot not in g and within[list(g)].sum() >= 2]
        if pairs:
            break
    later = [k for k in pairs[0] if within[k]][1]  # not the group's first within the limits
    focus = f"Only branch {later + 1}"
    drawing = SimpleNamespace(show_ghosts=True, focus=focus)
    assert LineDrawing.shown_ghosts(drawing, snapshot, 8).nonzero()[0].tolist() == [later]
    texts = numbered(snapshot, True, focus)
    assert texts[later] and all(not texts[k] for k in pairs[0] if k != later)
    everything = LineDrawing.shown_ghosts(SimpleNamespace(show_ghosts=True, focus=ALL_BRANCHES), snapshot, 8)
    assert not everything[later] and everything[[k for k in pairs[0] if within[k]][0]]
