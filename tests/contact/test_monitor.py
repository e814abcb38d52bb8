"""The contact check on poses made by hand: contacts at the right moment and place, the continuous check
between steps, the clearance and near misses, and what a safety margin changes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fleetsim.contact.geometry import Footprint, signed_distance
from fleetsim.contact.monitor import ContactMonitor

BOTH = np.array([True, True])


def _xs(*values: float) -> np.ndarray:
    return np.array(values, dtype=float)


def _box(x: float, y: float, heading: float, length: float, width: float) -> Footprint:
    return (x, y, heading, length / 2, width / 2)


@pytest.mark.parametrize(
    ("a", "b", "distance"),
    [
        ((0, 0, 0, 2, 1), (0, 1.1, 0, 2, 1), 0.1),  # side by side
        ((0, 0, 0, 2, 1), (2.5, 0, 0, 2, 1), 0.5),  # nose to tail
        ((0, 0, 0, 2, 1), (2, 1.5, 0, 2, 1), math.hypot(0, 0.5)),  # offset: corner to side
        ((0, 0, 0, 2, 2), (3, 3, 0, 2, 2), math.hypot(1, 1)),  # corner to corner
        ((0, 0, 0, 2, 1), (0, 0.8, 0, 2, 1), -0.2),  # overlapping by 0.2 m
        ((0, 0, 0, 2, 1), (0, 0, math.pi / 2, 2, 1), -1.5),  # a cross: the least way out
    ],
)
def test_the_signed_distance_of_two_footprints_is_exact(
    a: tuple[float, ...], b: tuple[float, ...], distance: float
) -> None:
    found, _, _ = signed_distance(_box(*a), _box(*b))
    assert found == pytest.approx(distance, abs=1e-12)


def _corners(f: Footprint) -> list[tuple[float, float]]:
    x, y, heading, length, width = f
    c, s = math.cos(heading), math.sin(heading)
    return [(x + u * length * c - v * width * s, y + u * length * s + v * width * c) for u, v in ((1, 1), (-1, 1), (-1, -1), (1, -1))]  # fmt: skip


def _to_segment(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    (px, py), (ax, ay), (bx, by) = p, a, b
    t = max(0.0, min(1.0, ((px - ax) * (bx - ax) + (py - ay) * (by - ay)) / ((bx - ax) ** 2 + (by - ay) ** 2)))
    return math.hypot(px - ax - t * (bx - ax), py - ay - t * (by - ay))


def test_the_distance_of_rectangles_apart_is_that_of_their_closest_sides() -> None:
    """Against a reference of its own kind: for two rectangles apart, the least distance between a
    corner of one and a side of the other, over all of them; random poses, many nearly parallel."""
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(3000):
        a = (0.0, 0.0, rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 1.5), rng.uniform(0.1, 0.8))
        parallel = a[2] + rng.choice([0.0, math.pi / 2, math.pi]) + rng.normal(0, 1e-3)
        heading = parallel if rng.uniform() < 0.5 else rng.uniform(-math.pi, math.pi)
        b = (*rng.uniform(-4, 4, 2), heading, rng.uniform(0.2, 1.5), rng.uniform(0.1, 0.8))
        found, x, y = signed_distance(a, b)
        ca, cb = _corners(a), _corners(b)
        sides_a, sides_b = list(zip(ca, ca[1:] + ca[:1], strict=True)), list(zip(cb, cb[1:] + cb[:1], strict=True))
        expected = min(
            [_to_segment(p, *side) for p in ca for side in sides_b] + [_to_segment(p, *side) for p in cb for side in sides_a]
        )  # fmt: skip
        if found > 1e-9:  # apart (overlaps are checked above)
            checked += 1
            assert found == pytest.approx(expected, abs=1e-9)
            # The place lies halfway between the two rectangles: as far from each as half the distance.
            place = (x, y)
            to_a = min(_to_segment(place, *side) for side in sides_a)
            to_b = min(_to_segment(place, *side) for side in sides_b)
            assert to_a == pytest.approx(found / 2, abs=1e-9) and to_b == pytest.approx(found / 2, abs=1e-9)
    assert checked > 2000


def test_a_rotated_footprint_is_measured_at_its_true_corners() -> None:
    # A 2 x 2 square turned 45 degrees reaches sqrt(2) from its centre along +x.
    found, *where = signed_distance(_box(0, 0, math.pi / 4, 2, 2), _box(3, 0, 0, 2, 2))
    assert found == pytest.approx(2 - math.sqrt(2))
    assert where == pytest.approx([(math.sqrt(2) + 2) / 2, 0.0])


def _lanes(gap: float, margin: float = 0.0) -> ContactMonitor:
    """Two 1 x 0.5 m vehicles on parallel lanes ``gap`` metres apart, driving side by side for a second."""
    monitor = ContactMonitor([1, 2], [1.0, 1.0], [0.5, 0.5], safety_margin=margin)
    y = 0.5 + gap
    monitor.begin(_xs(0, 0), _xs(0, y), _xs(0, 0))
    for k in range(10):
        x = 0.1 * (k + 1)
        monitor.step(0.1 * k, 0.1 * (k + 1), _xs(x, x), _xs(0, y), _xs(0, 0), BOTH)
    return monitor


def test_parallel_lanes_a_tenth_apart_never_touch_and_their_clearance_is_that_tenth() -> None:
    report = _lanes(0.1).report()
    assert report.contacts == ()
    assert report.clearance is not None and report.clearance.distance == pytest.approx(0.1)
    assert report.clearance.vehicles == (1, 2)
    assert [m.vehicles for m in report.near_misses] == [(1, 2)]  # 0.1 m is under the 0.5 m default


def test_a_safety_margin_turns_that_near_miss_into_a_contact() -> None:
    assert _lanes(0.1, margin=0.04).report().contacts == ()  # 0.1 - 2 x 0.04 = 0.02 m apart still
    [contact] = _lanes(0.1, margin=0.06).report().contacts  # 0.1 - 2 x 0.06 < 0: they touch
    assert contact.time == 0.0 and contact.depth == pytest.approx(0.02)


def test_head_on_at_5_m_s_with_half_second_steps_the_continuous_check_catches_what_no_step_shows() -> None:
    monitor = ContactMonitor([1, 2], [1.0, 1.0], [0.5, 0.5])
    # At t = 0 they are 1.8 m apart nose to nose; after one 0.5 s step each has driven 2.5 m: they have
    # passed through each other, and at both sampled moments their footprints are apart.
    assert monitor.begin(_xs(-1.4, 1.4), _xs(0, 0), _xs(0, math.pi)) == []
    before = signed_distance(_box(-1.4, 0, 0, 1, 0.5), _box(1.4, 0, math.pi, 1, 0.5))[0]
    after = signed_distance(_box(1.1, 0, 0, 1, 0.5), _box(-1.1, 0, math.pi, 1, 0.5))[0]
    assert before > 0 and after > 0
    [contact] = monitor.step(0.0, 0.5, _xs(1.1, -1.1), _xs(0, 0), _xs(0, math.pi), BOTH)
    # Noses meet when the centres are 1 m apart: 2.8 - 10 t = 1, t = 0.18 s, at x = 0.
    assert contact.time == pytest.approx(0.18, abs=1e-3)
    assert (contact.x, contact.y) == pytest.approx((0.0, 0.0), abs=1e-3)
    # At the deepest their centres met: the least way out is sideways, the width.
    assert contact.depth == pytest.approx(0.5, abs=0.01)
    assert monitor.report().contacts[0].until == 0.5


def test_the_same_pass_slowly_enough_apart_is_no_contact() -> None:
    monitor = ContactMonitor([1, 2], [1.0, 1.0], [0.5, 0.5])
    monitor.begin(_xs(-1.4, 1.4), _xs(0, 0.55), _xs(0, math.pi))  # lanes 0.05 m apart: they pass by
    assert monitor.step(0.0, 0.5, _xs(1.1, -1.1), _xs(0, 0.55), _xs(0, math.pi), BOTH) == []
    clearance = monitor.report().clearance
    assert clearance is not None and clearance.distance == pytest.approx(0.05, abs=1e-3)


def test_a_turn_in_place_clips_a_standing_vehicles_corner() -> None:
    monitor = ContactMonitor([1, 2], [2.0, 1.0], [0.5, 0.5])
    # Vehicle 1 (2 m long) turns 90 degrees on the spot in one step; vehicle 2 stands beside it, its near
    # side at y = 0.95: clear of vehicle 1 at both ends of the turn, not in between.
    assert monitor.begin(_xs(0, 0), _xs(0, 1.2), _xs(0, 0)) == []
    [contact] = monitor.step(0.0, 0.1, _xs(0, 0), _xs(0, 1.2), _xs(math.pi / 2, 0), np.array([True, False]))
    # Vehicle 1's corner (1, 0.25) reaches y = 0.95 when sin(a) + 0.25 cos(a) = 0.95.
    angle = next(a for a in np.linspace(0, math.pi / 2, 100001) if math.sin(a) + 0.25 * math.cos(a) >= 0.95)
    assert contact.time == pytest.approx(0.1 * angle / (math.pi / 2), abs=1e-3)
    assert contact.y == pytest.approx(0.95, abs=1e-3)
    apart = ContactMonitor([1, 2], [2.0, 1.0], [0.5, 0.5])
    apart.begin(_xs(0, 0), _xs(0, 1.3), _xs(0, 0))  # standing 0.1 m farther: the corner passes clear
    assert apart.step(0.0, 0.1, _xs(0, 0), _xs(0, 1.3), _xs(math.pi / 2, 0), np.array([True, False])) == []


def test_a_contact_ends_when_they_part_and_a_new_touch_is_a_new_contact() -> None:
    monitor = ContactMonitor([1, 2], [1.0, 1.0], [0.5, 0.5])
    monitor.begin(_xs(0, 2), _xs(0, 0), _xs(0, 0))
    path = [0.5, 1.2, 1.4, 0.5, 1.2]  # vehicle 1 drives in, stays in, backs out, drives in again
    for k, x in enumerate(path):
        monitor.step(0.1 * k, 0.1 * (k + 1), _xs(x, 2), _xs(0, 0), _xs(0, 0), np.array([True, False]))
    first, second = monitor.report().contacts
    assert first.until == pytest.approx(0.4) and first.depth == pytest.approx(0.4)
    assert second.time > first.until and second.until is None  # still touching at the end


def test_vehicles_far_apart_have_no_clearance_within_reach_and_no_near_miss() -> None:
    monitor = ContactMonitor([1, 2, 3], [1.0] * 3, [0.5] * 3)
    monitor.begin(_xs(0, 10, 20), _xs(0, 0, 0), _xs(0, 0, 0))
    monitor.step(0.0, 0.1, _xs(0.1, 10.1, 20.1), _xs(0, 0, 0), _xs(0, 0, 0), np.ones(3, dtype=bool))
    report = monitor.report()
    assert report.clearance is None and report.near_misses == () and report.contacts == ()


@pytest.mark.parametrize("spacing", [5.0, 5000.0])  # a compact row, and one on a vast map (few vehicles per cell)
def test_the_broad_phase_finds_the_one_close_pair_among_many(spacing: float) -> None:
    rng = np.random.default_rng(7)
    count = 400
    x, y = np.arange(count) * spacing, rng.uniform(0, 1, count)  # nobody near anybody
    x[300] = x[299] + 1.05  # but vehicle 300 sits 0.05 m behind vehicle 299
    ids = list(range(1, count + 1))
    monitor = ContactMonitor(ids, [1.0] * count, [0.5] * count)
    y[300] = y[299]
    monitor.begin(x, y, np.zeros(count))
    candidates = monitor._candidates(monitor._poses, 0.0)  # type: ignore[arg-type]
    assert len(candidates[0]) < 3 * count  # neighbours only, not all 79,800 pairs
    clearance = monitor.report().clearance
    assert clearance is not None and clearance.vehicles == (300, 301)
    assert clearance.distance == pytest.approx(0.05)


@pytest.mark.parametrize("area", [60.0, 1e6])  # metres square: cells counted in an array, and looked up
def test_the_broad_phase_misses_no_pair_that_could_matter(area: float) -> None:
    # Clusters of three vehicles within a few metres of each other, in every direction from each other,
    # the clusters scattered over the area: every pair whose circles come within reach is a candidate.
    rng = np.random.default_rng(11)
    centres = rng.uniform(0, area, (150, 2))
    x = (centres[:, None, 0] + rng.uniform(-2, 2, (150, 3))).ravel()
    y = (centres[:, None, 1] + rng.uniform(-2, 2, (150, 3))).ravel()
    count = len(x)
    monitor = ContactMonitor(list(range(count)), [1.0] * count, [0.5] * count)
    monitor.begin(x, y, rng.uniform(-math.pi, math.pi, count))
    i, j = monitor._candidates(monitor._poses, 0.0)  # type: ignore[arg-type]
    found = set(zip(i.tolist(), j.tolist(), strict=True))
    radius = math.hypot(0.5, 0.25)
    expected = {
        (p, q)
        for p in range(count)
        for q in range(p + 1, count)
        if math.hypot(x[q] - x[p], y[q] - y[p]) - 2 * radius < monitor.reach
    }
    assert expected and expected <= found
    assert len(i) == len(found) and all(p < q for p, q in found)  # each pair once, in order


@pytest.mark.parametrize(
    ("count", "told"),
    [(40, False), (16, False), (60, True)],  # the arrays; a few, and a fleet told what moved, in plain Python
)
def test_pairs_left_unlooked_at_could_not_have_mattered(count: int, told: bool) -> None:
    """The monitor keeps its candidate pairs over steps and looks at a pair again only when its vehicles
    have moved enough to close the gap to what counts. Against every pair's exact distance at every step's
    end, over a random walk of a crowd (some standing, some turning, some driving): no contact, near miss
    or closer clearance is missed."""
    rng = np.random.default_rng(5)
    steps, dt = 150, 0.1
    side = 12.0 * math.sqrt(count / 40)  # as crowded either way
    x, y = rng.uniform(0, side, count), rng.uniform(0, side, count)
    heading = rng.uniform(-math.pi, math.pi, count)
    lengths, widths = rng.uniform(0.6, 1.4, count), rng.uniform(0.4, 0.8, count)
    monitor = ContactMonitor(list(range(count)), lengths.tolist(), widths.tolist())
    monitor.begin(x, y, heading)
    speed = rng.uniform(0, 1.5, count) * (rng.uniform(size=count) < 0.7)  # some stand still
    closest: dict[tuple[int, int], float] = {}
    touched: set[tuple[int, int]] = set()
    for k in range(steps):
        turn = rng.normal(0, 0.2, count)
        turning = rng.uniform(size=count) < 0.5
        heading = heading + turn * turning
        moved = (speed > 0) | (rng.uniform(size=count) < 0.1)
        x = x + speed * dt * np.cos(heading)
        y = y + speed * dt * np.sin(heading)
        if told:  # (told of every vehicle whose pose changed, as the loop tells it)
            at = (moved | turning).nonzero()[0].tolist()
            monitor.step_moved(k * dt, (k + 1) * dt, at, [(x[v], y[v], heading[v]) for v in at])
        else:
            monitor.step(k * dt, (k + 1) * dt, x, y, heading, moved)
        shapes = [(x[n], y[n], heading[n], lengths[n] / 2, widths[n] / 2) for n in range(count)]
        for p in range(count):
            for q in range(p + 1, count):
                d = signed_distance(shapes[p], shapes[q])[0]
                if d <= 1e-4:
                    touched.add((p, q))
                closest[(p, q)] = min(d, closest.get((p, q), math.inf))
    report = monitor.report()
    assert touched and touched <= {c.vehicles for c in report.contacts}
    misses = {m.vehicles: m.distance for m in report.near_misses}
    expected = {pair: d for pair, d in closest.items() if 1e-4 < d < report.near_miss and pair not in touched}
    assert expected
    for pair, d in expected.items():
        assert pair in misses or pair in {c.vehicles for c in report.contacts}
        assert misses.get(pair, 0.0) <= d + 1e-9
    assert report.clearance is not None and report.clearance.distance <= max(min(closest.values()), 0.0) + 1e-9


def test_a_pair_drawing_apart_after_its_closest_approach_is_looked_at_again_only_when_it_could_beat_it() -> None:
    """Two vehicles side by side 0.3 m apart (a near miss, within the 0.5 m default): one draws away
    1 cm a step. Nothing it does until 0.5 m can beat the 0.3 m on record, so the pair is looked at again
    only when it has moved far enough to have come closer than that; when it turns back and comes within
    0.25 m, that is looked at and recorded."""
    monitor = ContactMonitor([1, 2], [2.0, 2.0], [1.0, 1.0])
    monitor.begin(_xs(0, 0), _xs(0, 1.3), _xs(0, 0))
    still = np.array([False, True])
    for k in range(1, 16):  # away, to 0.45 m apart
        monitor.step(0.1 * (k - 1), 0.1 * k, _xs(0, 0), _xs(0, 1.3 + 0.01 * k), _xs(0, 0), still)
    away = monitor.looked
    assert 1 <= away <= 5  # at 0.31, 0.32, 0.34, 0.38: each doubling the excess over the record
    for k in range(16, 36):  # and back, to 0.25 m apart
        monitor.step(0.1 * (k - 1), 0.1 * k, _xs(0, 0), _xs(0, 1.45 - 0.01 * (k - 15)), _xs(0, 0), still)
    [miss] = monitor.report().near_misses
    assert miss.distance == pytest.approx(0.25) and miss.time == pytest.approx(3.5)
    assert monitor.looked - away >= 5  # closing in from 0.30 to 0.25: every step beats the record


def _walk(
    monitor: ContactMonitor, seed: int, count: int, told_what_moved: bool = False, moving: float = 0.7
) -> list[list[object]]:
    """A seeded random walk of ``count`` vehicles, bumping into each other, each moving in a step with
    probability ``moving``; each step's fresh contacts (``told_what_moved``: the monitor is given only the
    moved vehicles' poses, as the loop gives them)."""
    rng = np.random.default_rng(seed)
    side = 2.0 + 0.4 * count  # metres square: they stay in it (pressed against its walls)
    x, y = rng.uniform(0, side, count), rng.uniform(0, side, count)
    heading = rng.uniform(-math.pi, math.pi, count)
    found: list[list[object]] = [list(monitor.begin(x, y, heading))]
    speed = rng.uniform(0, 2.0, count)
    for k in range(300):
        moved = rng.uniform(size=count) < moving
        turn = rng.normal(0, 0.3, count) * moved
        heading = np.remainder(heading + turn + math.pi, 2 * math.pi) - math.pi  # wrapping round at times
        x = np.clip(x + np.where(moved, speed * 0.1 * np.cos(heading), 0.0), 0.0, side)
        y = np.clip(y + np.where(moved, speed * 0.1 * np.sin(heading), 0.0), 0.0, side)
        if told_what_moved:
            at = moved.nonzero()[0].tolist()
            poses = [(float(x[v]), float(y[v]), float(heading[v])) for v in at]
            found.append(list(monitor.step_moved(k * 0.1, (k + 1) * 0.1, at, poses)))
        else:
            found.append(list(monitor.step(k * 0.1, (k + 1) * 0.1, x, y, heading, moved)))
    return found


@pytest.mark.parametrize("count", range(2, 17))
def test_a_fleet_of_a_few_judged_in_plain_python_gives_what_the_arrays_give(count: int) -> None:
    sizes = np.random.default_rng(count).uniform(0.5, 1.5, (2, count)).tolist()
    contacts = 0
    for seed in range(3):
        few, told, arrays = (ContactMonitor(list(range(1, count + 1)), *sizes) for _ in range(3))
        arrays._few = False  # judged in arrays, as a larger fleet is
        assert few.few and told.few and not arrays.few
        expected = _walk(arrays, seed, count)
        assert _walk(few, seed, count) == expected
        assert _walk(told, seed, count, told_what_moved=True) == expected  # as the loop tells a few
        assert few.report() == told.report() == arrays.report()
        contacts += len(few.report().contacts)
    assert contacts > 0


@pytest.mark.parametrize(("count", "moving"), [(20, 0.2), (40, 0.6), (100, 0.1), (100, 0.4), (80, 0.8)])
def test_a_fleet_told_what_moved_gives_what_the_arrays_give(count: int, moving: float) -> None:
    """Told only what moved, a larger fleet is judged in plain Python while few of it move, and in arrays
    otherwise (around 40 vehicles, from one step to the next): the same contacts step by step, and the same
    report, as the arrays give it every step."""
    sizes = np.random.default_rng(count).uniform(0.5, 1.5, (2, count)).tolist()
    contacts = 0
    for seed in range(2):
        told, arrays = (ContactMonitor(list(range(1, count + 1)), *sizes) for _ in range(2))
        assert not told.few
        expected = _walk(arrays, seed, count, moving=moving)
        assert _walk(told, seed, count, told_what_moved=True, moving=moving) == expected
        assert told.report() == arrays.report()
        contacts += len(told.report().contacts)
    assert contacts > 0
