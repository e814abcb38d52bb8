"""The speed profile (SPEC §8, thesis eqs. 12 and 14): stop times, exact areas, and stepping to the stop."""

from __future__ import annotations

import math
from itertools import pairwise

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.motion import SpeedProfile

DT = 0.1

# One profile of each kind (v0, a, vmax, s), plus one with unround numbers.
EVERY_KIND = [
    pytest.param(0.0, 0.5, 1.0, 1.0, id="triangle"),
    pytest.param(0.6, 0.5, 1.0, 10.0, id="trapezoid"),
    pytest.param(1.0, 0.5, 1.0, 0.3, id="brake"),
    pytest.param(0.2, 2.0, 1.5, 3.7, id="odd-numbers"),
]


def _eq12(v0: float, a: float, s: float) -> float:
    return (2.0 * math.sqrt(a * s + v0 * v0 / 2.0) - v0) / a


def _eq14(v0: float, a: float, vmax: float, s: float) -> float:
    return (v0 * v0 - 2.0 * v0 * vmax + 2.0 * vmax * vmax + 2.0 * a * s) / (2.0 * a * vmax)


def _boundaries(profile: SpeedProfile) -> list[float]:
    return [profile.accelerate_until, profile.brake_from, profile.stop_time]


def _simulate(profile: SpeedProfile) -> tuple[float, float]:
    """Step by DT until the distance is covered; the sum of advances and the end time of the last step."""
    covered, t = 0.0, 0.0
    for _ in range(100_000):
        covered += profile.advance(t, t + DT)
        t += DT
        if profile.distance_at(t) >= profile.distance:
            return covered, t
    raise AssertionError("profile never reached its distance")


@pytest.mark.parametrize(
    ("v0", "a", "vmax", "s"),
    [
        pytest.param(0.0, 0.5, 1.0, 1.0, id="from-rest"),
        pytest.param(0.4, 0.5, 1.0, 1.0, id="moving-start"),
        pytest.param(1.0, 0.5, 1.0, 1.0, id="at-stopping-distance"),
    ],
)
def test_triangle_stop_time_is_thesis_eq_12(v0: float, a: float, vmax: float, s: float) -> None:
    profile = SpeedProfile.plan(v0, a, vmax, s)
    assert profile.kind == "triangle"
    assert profile.stop_time == pytest.approx(_eq12(v0, a, s), rel=1e-12)
    assert profile.peak == pytest.approx(math.sqrt(a * s + v0 * v0 / 2.0), rel=1e-12)
    assert profile.accelerate_until == profile.brake_from
    assert profile.deceleration == a


@pytest.mark.parametrize(
    ("v0", "a", "vmax", "s"),
    [
        pytest.param(0.0, 0.5, 1.0, 10.0, id="from-rest"),
        pytest.param(0.6, 0.5, 1.0, 10.0, id="moving-start"),
        pytest.param(1.0, 0.5, 1.0, 10.0, id="already-at-max-speed"),
    ],
)
def test_trapezoid_stop_time_is_thesis_eq_14(v0: float, a: float, vmax: float, s: float) -> None:
    profile = SpeedProfile.plan(v0, a, vmax, s)
    assert profile.kind == "trapezoid"
    assert profile.stop_time == pytest.approx(_eq14(v0, a, vmax, s), rel=1e-12)
    assert profile.peak == vmax
    assert profile.accelerate_until == pytest.approx((vmax - v0) / a)
    assert profile.brake_from == pytest.approx(profile.stop_time - vmax / a)


def test_trapezoid_from_rest_matches_hand_computed_phases() -> None:
    # 0 → 1 m/s in 2 s (1 m), cruise 8 m in 8 s, 1 → 0 m/s in 2 s (1 m).
    profile = SpeedProfile.plan(0.0, 0.5, 1.0, 10.0)
    assert (profile.accelerate_until, profile.brake_from, profile.stop_time) == (2.0, 10.0, 12.0)
    assert profile.distance_at(2.0) == 1.0
    assert profile.distance_at(10.0) == 9.0
    assert profile.distance_at(6.0) == 5.0


@pytest.mark.parametrize("v0", [0.0, 0.3, 0.9])
def test_peak_equal_to_max_speed_gives_the_same_stop_time_from_both_formulas(v0: float) -> None:
    a, vmax = 0.5, 1.0
    s = (vmax * vmax - v0 * v0 / 2.0) / a  # makes vp == vmax
    assert _eq12(v0, a, s) == pytest.approx(_eq14(v0, a, vmax, s), rel=1e-12)
    profile = SpeedProfile.plan(v0, a, vmax, s)
    assert profile.peak == pytest.approx(vmax, rel=1e-12)
    assert profile.stop_time == pytest.approx(_eq14(v0, a, vmax, s), rel=1e-12)
    nudged = SpeedProfile.plan(v0, a, vmax, s * (1.0 + 1e-12))
    assert nudged.stop_time == pytest.approx(profile.stop_time, rel=1e-9)


@pytest.mark.parametrize(("v0", "a", "vmax", "s"), EVERY_KIND)
def test_speed_is_continuous_at_phase_boundaries_and_zero_at_stop(v0: float, a: float, vmax: float, s: float) -> None:
    profile = SpeedProfile.plan(v0, a, vmax, s)
    assert profile.speed_at(0.0) == v0
    assert profile.speed_at(profile.stop_time) == 0.0
    assert profile.speed_at(profile.stop_time + 5.0) == 0.0
    eps = 1e-9
    for t in _boundaries(profile)[:2]:
        if 0.0 < t < profile.stop_time:
            assert profile.speed_at(t - eps) == pytest.approx(profile.speed_at(t + eps), abs=1e-6)
    assert profile.speed_at(profile.stop_time - eps) == pytest.approx(0.0, abs=1e-6)
    top = max(profile.speed_at(i * profile.stop_time / 1000) for i in range(1001))
    assert top == pytest.approx(profile.peak, abs=profile.acceleration * profile.stop_time / 1000)
    assert profile.speed_at(profile.accelerate_until) == pytest.approx(profile.peak, rel=1e-12)


@pytest.mark.parametrize(("v0", "a", "vmax", "s"), EVERY_KIND)
def test_distance_at_stop_time_is_exactly_the_distance(v0: float, a: float, vmax: float, s: float) -> None:
    profile = SpeedProfile.plan(v0, a, vmax, s)
    assert profile.distance_at(0.0) == 0.0
    assert profile.distance_at(profile.stop_time) == s
    assert profile.distance_at(profile.stop_time + 1.0) == s
    assert profile.distance_at(-1.0) == 0.0


def test_distance_at_equals_numeric_area_under_speed() -> None:
    profile = SpeedProfile.plan(0.3, 0.7, 1.2, 5.0)
    n = 20_000
    h = profile.stop_time / n
    # Midpoint rule is exact on linear pieces except the cells containing a phase boundary.
    area = sum(profile.speed_at((i + 0.5) * h) for i in range(n // 2)) * h
    assert profile.distance_at(n // 2 * h) == pytest.approx(area, abs=1e-6)


@pytest.mark.parametrize(
    ("v0", "a", "vmax", "s"),
    [
        pytest.param(0.0, 0.5, 1.0, 1.0, id="triangle-from-rest"),
        pytest.param(0.5, 0.5, 1.0, 2.0, id="triangle-moving"),
        pytest.param(0.0, 0.5, 1.0, 10.0, id="trapezoid-from-rest"),
        pytest.param(0.8, 1.3, 2.0, 17.3, id="trapezoid-moving"),
    ],
)
def test_stepping_by_dt_covers_the_distance_and_stops_within_one_step_of_tz(
    v0: float, a: float, vmax: float, s: float
) -> None:
    profile = SpeedProfile.plan(v0, a, vmax, s)
    covered, stopped = _simulate(profile)
    assert covered == pytest.approx(s, abs=1e-9)
    assert abs(stopped - profile.stop_time) < DT + 1e-9


def test_zero_distance_from_rest_stops_at_once() -> None:
    profile = SpeedProfile.plan(0.0, 0.5, 1.0, 0.0)
    assert profile.stop_time == 0.0
    assert profile.speed_at(0.0) == 0.0
    assert profile.distance_at(1.0) == 0.0
    assert profile.advance(0.0, DT) == 0.0


@pytest.mark.parametrize("s", [0.3, 1e-6, 1e-300])
def test_distance_shorter_than_stopping_distance_brakes_harder_to_stop_within_it(s: float) -> None:
    v0, a = 1.0, 0.5  # stopping distance 1 m
    profile = SpeedProfile.plan(v0, a, 1.0, s)
    assert profile.kind == "brake"
    assert profile.peak == v0
    assert profile.deceleration == pytest.approx(v0 * v0 / (2.0 * s))
    assert profile.deceleration > a
    assert profile.stop_time == pytest.approx(2.0 * s / v0)
    samples = [i * profile.stop_time / 50 for i in range(51)]
    for t in samples:
        assert not math.isnan(profile.speed_at(t))
        assert 0.0 <= profile.distance_at(t) <= s
    assert profile.speed_at(profile.stop_time) == 0.0
    assert profile.distance_at(profile.stop_time) == s


def test_zero_distance_while_moving_stops_instantly_without_nan() -> None:
    profile = SpeedProfile.plan(1.0, 0.5, 1.0, 0.0)
    assert profile.kind == "brake"
    assert profile.stop_time == 0.0
    assert profile.deceleration == math.inf
    assert profile.speed_at(0.0) == 0.0
    assert profile.distance_at(0.0) == 0.0
    assert profile.advance(0.0, DT) == 0.0


def test_v0_a_rounding_error_above_max_speed_is_clamped() -> None:
    profile = SpeedProfile.plan(1.0 + 1e-12, 0.5, 1.0, 5.0)
    assert profile.v0 == 1.0
    assert profile.speed_at(0.0) == 1.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        pytest.param({"v0": -0.1}, r"v0=-0\.1 must be non-negative", id="negative-v0"),
        pytest.param({"v0": math.nan}, r"v0=nan must", id="nan-v0"),
        pytest.param({"acceleration": 0.0}, r"acceleration=0\.0 must be positive", id="zero-acceleration"),
        pytest.param({"acceleration": math.inf}, r"acceleration=inf must", id="infinite-acceleration"),
        pytest.param({"max_speed": -1.0}, r"max_speed=-1\.0 must be positive", id="negative-max-speed"),
        pytest.param({"distance": -1.0}, r"distance=-1\.0 must be non-negative", id="negative-distance"),
        pytest.param({"distance": math.inf}, r"distance=inf must", id="infinite-distance"),
        pytest.param({"v0": 1.5}, r"v0=1\.5 must not exceed max_speed=1\.0", id="v0-above-max-speed"),
    ],
)
def test_invalid_parameters_raise_value_error(kwargs: dict[str, float], message: str) -> None:
    params = {"v0": 0.0, "acceleration": 0.5, "max_speed": 1.0, "distance": 1.0} | kwargs
    with pytest.raises(ValueError, match=message):
        SpeedProfile.plan(**params)


def test_advance_backwards_in_time_or_at_nan_raises() -> None:
    profile = SpeedProfile.plan(0.0, 0.5, 1.0, 1.0)
    with pytest.raises(ValueError, match=r"t1=0\.5 must not be before t0=1\.0"):
        profile.advance(1.0, 0.5)
    with pytest.raises(ValueError, match=r"t1=8\.0 must not be before t0=9\.0"):
        profile.advance(9.0, 8.0)  # both past the stop, still an error
    with pytest.raises(ValueError, match=r"t=nan must be a number"):
        profile.distance_at(math.nan)


@st.composite
def _profiles(draw: st.DrawFn) -> SpeedProfile:
    max_speed = draw(st.floats(0.01, 50.0))
    v0 = draw(st.one_of(st.just(0.0), st.just(max_speed), st.floats(0.0, max_speed)))
    acceleration = draw(st.floats(0.01, 20.0))
    distance = draw(st.one_of(st.just(0.0), st.floats(0.0, 1e-6), st.floats(0.0, 1000.0)))
    return SpeedProfile.plan(v0, acceleration, max_speed, distance)


@settings(max_examples=300, deadline=None)
@given(profile=_profiles(), fractions=st.lists(st.floats(-0.1, 1.1), min_size=2, max_size=30))
def test_distance_is_monotone_and_bounded_and_speed_stays_in_range(
    profile: SpeedProfile, fractions: list[float]
) -> None:
    # Probe the phase boundaries (and just around them) as well as random times.
    times = sorted(
        [f * profile.stop_time for f in fractions]
        + [b + d for b in _boundaries(profile) for d in (-1e-12, 0.0, 1e-12)]
        + [0.0]
    )
    distances = [profile.distance_at(t) for t in times]
    assert all(earlier <= later for earlier, later in pairwise(distances))
    assert all(0.0 <= d <= profile.distance for d in distances)
    assert profile.distance_at(profile.stop_time) == profile.distance
    for t in times:
        speed = profile.speed_at(t)
        assert 0.0 <= speed <= profile.max_speed + 1e-9
