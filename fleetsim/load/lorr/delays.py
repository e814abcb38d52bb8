"""A 2026 problem's ``delayConfig`` (random delays of robots) and fleetsim's counterpart: random stops.

The League delays robots at random (Start-Kit ``DelayGenerator``): ``seed``; ``minDelay`` and ``maxDelay``
(timesteps, ``0 < minDelay <= maxDelay``); ``eventModel`` ``bernoulli`` (each robot not delayed starts a
delay with probability ``pDelay`` at each timestep) or ``poisson`` (a Poisson number of robots per
timestep, at rate ``poissonLambda``, or ``teamSize × pDelay`` without it); ``durationModel`` ``uniform``
or ``gaussian`` (mean ``minDelay + (maxDelay − minDelay)·gaussMeanRatio``, deviation
``(maxDelay − minDelay)·gaussStdRatio``, rounded and clamped to the range).

fleetsim's random disturbances (:class:`~fleetsim.scenario.RandomDisturbances`) stop a vehicle at random
for a duration drawn uniformly, on average ``stops_per_vehicle_hour`` times an hour. The mapping, at one
timestep per second: ``pDelay × 3600`` stops per vehicle hour (``poissonLambda / teamSize × 3600`` for the
Poisson model), standing ``[minDelay, maxDelay]`` seconds, seeded by ``seed``. What differs is named in
the run's notes: the durations are uniform whatever ``durationModel`` says, and fleetsim draws its own
numbers (the same stops on every machine, but not the Start-Kit's).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from fleetsim.errors import ScenarioFileError
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.scenario import RandomDisturbances

if TYPE_CHECKING:
    from fleetsim.load.lorr.places import KeyPlaces

__all__ = ["DELAY_KEYS", "DelayConfig", "delay_disturbances", "parse_delays"]

DELAY_KEYS = (
    "seed",
    "minDelay",
    "maxDelay",
    "eventModel",
    "pDelay",
    "poissonLambda",
    "durationModel",
    "gaussMeanRatio",
    "gaussStdRatio",
)
_WITHIN = "delayConfig"


@dataclass(frozen=True, slots=True)
class DelayConfig:
    """A ``delayConfig`` block, checked; the Start-Kit's defaults where a key is absent."""

    seed: int = 0
    min_delay: int = 1
    max_delay: int = 1
    event_model: str = "bernoulli"
    p_delay: float = 0.0
    poisson_lambda: float | None = None
    duration_model: str = "uniform"
    gauss_mean_ratio: float = 0.5
    gauss_std_ratio: float = 0.0


def parse_delays(raw: object, places: KeyPlaces) -> DelayConfig:
    """Check a ``delayConfig`` value; every problem is located at its key."""
    if not isinstance(raw, dict):
        raise ScenarioFileError(f"delayConfig must be an object, not {raw!r}"[:120], places.at(_WITHIN))
    errors = ErrorCollector()
    for key in raw:
        if key not in DELAY_KEYS:
            msg = (
                f"unknown key {key!r} of delayConfig{did_you_mean(key, DELAY_KEYS)} (its keys: {', '.join(DELAY_KEYS)})"
            )
            errors.add(ScenarioFileError(msg, places.at(key, _WITHIN)))
    values: dict[str, object] = {}
    checks: dict[str, Callable[[Any], bool]] = {
        "seed": lambda v: _is_whole(v) and v >= 0,
        "minDelay": lambda v: _is_whole(v) and v > 0,
        "maxDelay": lambda v: _is_whole(v) and v > 0,
        "eventModel": lambda v: v in ("bernoulli", "poisson"),
        "pDelay": lambda v: _is_number(v) and 0.0 <= v <= 1.0,
        "poissonLambda": lambda v: _is_number(v) and v >= 0.0,
        "durationModel": lambda v: v in ("uniform", "gaussian"),
        "gaussMeanRatio": lambda v: _is_number(v) and 0.0 <= v <= 1.0,
        "gaussStdRatio": lambda v: _is_number(v) and v >= 0.0,
    }
    rules = {
        "seed": "a whole number >= 0",
        "minDelay": "a whole number of timesteps > 0",
        "maxDelay": "a whole number of timesteps > 0",
        "eventModel": "'bernoulli' or 'poisson'",
        "pDelay": "a number from 0 to 1",
        "poissonLambda": "a number >= 0",
        "durationModel": "'uniform' or 'gaussian'",
        "gaussMeanRatio": "a number from 0 to 1",
        "gaussStdRatio": "a number >= 0",
    }
    for key, check in checks.items():
        if key not in raw:
            continue
        value = raw[key]
        if check(value):
            values[key] = value
        else:
            errors.add(ScenarioFileError(f"delayConfig.{key}={value!r} must be {rules[key]}", places.at(key, _WITHIN)))
    errors.raise_if_any()
    config = DelayConfig(
        seed=int(values.get("seed", 0)),  # type: ignore[call-overload]
        min_delay=int(values.get("minDelay", 1)),  # type: ignore[call-overload]
        max_delay=int(values.get("maxDelay", 1)),  # type: ignore[call-overload]
        event_model=str(values.get("eventModel", "bernoulli")),
        p_delay=float(values.get("pDelay", 0.0)),  # type: ignore[arg-type]
        poisson_lambda=float(values["poissonLambda"]) if "poissonLambda" in values else None,  # type: ignore[arg-type]
        duration_model=str(values.get("durationModel", "uniform")),
        gauss_mean_ratio=float(values.get("gaussMeanRatio", 0.5)),  # type: ignore[arg-type]
        gauss_std_ratio=float(values.get("gaussStdRatio", 0.0)),  # type: ignore[arg-type]
    )
    if config.max_delay < config.min_delay:
        msg = f"delayConfig.maxDelay={config.max_delay} must be >= minDelay ({config.min_delay})"
        raise ScenarioFileError(msg, places.at("maxDelay", _WITHIN))
    return config


def _is_whole(value: object) -> bool:
    return _is_number(value) and float(value).is_integer()  # type: ignore[arg-type]


def _is_number(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


def delay_disturbances(
    config: DelayConfig, team_size: int, timestep: float
) -> tuple[RandomDisturbances | None, tuple[str, ...]]:
    """fleetsim's random stops for ``config`` (``None`` when no delay can happen) and the notes on what
    differs (see the module docstring); ``timestep``: seconds per League timestep."""
    if config.event_model == "poisson":
        rate = config.poisson_lambda if config.poisson_lambda is not None else team_size * config.p_delay
        per_step = rate / max(team_size, 1)
        how = f"poisson: {rate:g} robots per timestep over {team_size} robots"
    else:
        per_step = config.p_delay
        how = f"bernoulli: pDelay={config.p_delay:g} per robot and timestep"
    notes = [
        f"delayConfig ({how}, {config.min_delay}-{config.max_delay} timesteps, seed {config.seed}) becomes "
        "random stops drawn by fleetsim from the same seed: the same stops on every machine, not the Start-Kit's"
    ]
    if config.duration_model == "gaussian" and config.min_delay != config.max_delay:
        notes.append(
            f"delayConfig.durationModel 'gaussian' (mean ratio {config.gauss_mean_ratio:g}, std ratio "
            f"{config.gauss_std_ratio:g}) is not mapped: fleetsim's stop durations are uniform in [minDelay, maxDelay]"
        )
    if per_step <= 0.0:
        return None, tuple(notes)
    per_hour = per_step * 3600.0 / timestep
    low, high = config.min_delay * timestep, config.max_delay * timestep
    return RandomDisturbances(seed=config.seed, stops_per_vehicle_hour=per_hour, stop=(low, high)), tuple(notes)
