"""Where a run's orders come from, step by step: ``orders.csv`` releases and generated order streams.

Time is the run's step grid: step ``k`` starts at ``k × time_step`` (the loop's ``now``, bit for bit), and an
order is released at the start of a step, never between two. An ``orders.csv`` order is released at the
first step whose start is at or after its ``release`` (less 1e-9): a release between two step starts takes
effect at the next one (``release: 1.05`` with ``time_step: 0.1`` comes at step 11, at 1.1 s); its
``release`` stays as written.

Generated orders (an :class:`~fleetsim.orders.OrderStream`) are called ``s1``, ``s2``, ... in release
order, and released at a step start, which is their ``release``; ``deadline`` is ``release`` plus the
stream's. Arrival processes:

* ``poisson``: every step whose start lies in ``[start, until]`` releases ``Poisson(rate / 3600 ×
  time_step)`` orders: one step's length of arrivals, on the grid.
* ``interval``: one order is due every ``interval`` seconds from ``start`` (at ``start + n × interval``)
  and released at the first step starting at or after that; two due in one step are both released then.
* ``pool``: ``open`` orders at the first step starting at or after ``start``, then one more for each of
  them completed, at the start of the next step (after ``completed`` is told, at the next ``due``).

No release after ``until``; at most ``limit`` orders in all.

``orders.csv`` orders may be released as a closed pool too (``pool=N``, as a League of Robot Runners
problem reveals its tasks): in file order, whatever their ``release``, the first ``N`` at step 0, then the
next one for each of them completed, at the start of the next step.

Determinism on every platform and Python ≥ 3.2, as the random disturbances draw
(:mod:`fleetsim.sim.disturbances`): two generators seeded from strings (by SHA-512),
``random.Random(f"fleetsim-orders/{seed}/arrivals")`` for when orders come and
``random.Random(f"fleetsim-orders/{seed}/contents")`` for what they hold, drawn order by order, so the
n-th order's stops are the same whatever the time step. Only integer draws (``getrandbits``) and
correctly rounded arithmetic:

* Poisson counts by inverse transform: one ``getrandbits(64)`` per step against the thresholds
  ``floor(P(N ≤ k) × 2⁶⁴)``, computed once per stream in :mod:`decimal` at 40 digits (its ``exp`` is
  correctly rounded, so not even the one ``exp`` per stream is left to the platform's libm).
* A count in ``[lo, hi]``: ``lo + below(hi − lo + 1)``, where ``below(n)`` draws ``n.bit_length()`` bits
  until the number is below ``n`` (no draw when ``lo == hi``).
* A stop's segment: from the union of the named station sets (segments ascending, each once; a segment
  in several sets has the weight of the first set the draw names that holds it), leaving out the
  previous stop's segment when another is left. Uniformly, or by weight: the float weights are turned
  into integers exactly (:class:`fractions.Fraction`, over their common denominator) and one
  ``below(total)`` picks the segment. No draw when one segment is left.
* A dwell in ``[lo, hi]``: ``lo + (hi − lo) × getrandbits(32) / 2³²`` rounded to milliseconds (no draw
  when ``lo == hi``).

Per order, for each stop draw in turn: its count, then per stop its segment and its dwell.
"""

from __future__ import annotations

import random
import re
from bisect import bisect_right
from collections.abc import Mapping
from decimal import ROUND_FLOOR, Context, Decimal
from fractions import Fraction
from math import gcd, lcm
from typing import Any

from fleetsim.orders import Order, OrderStream, Station, Stop, StopDraw

__all__ = ["OrderSource", "poisson_thresholds"]

_EPS = 1e-9
_BITS = 64  # bits of one Poisson draw
_GENERATED = re.compile(r"s[1-9][0-9]*")  # the ids generated orders get


def poisson_thresholds(mean: float) -> tuple[int, ...]:
    """``floor(P(N ≤ k) × 2⁶⁴)`` for ``k = 0, 1, ...`` of ``N ~ Poisson(mean)``, the last one ``2⁶⁴``.

    A draw ``u = getrandbits(64)`` gives ``N = bisect_right(thresholds, u)``. Exact decimal arithmetic at
    40 digits (``Decimal.exp`` is correctly rounded): the same integers on every platform.
    """
    if not mean > 0.0:
        msg = f"mean={mean!r} must be > 0"
        raise ValueError(msg)
    context = Context(prec=40)
    lam = context.create_decimal_from_float(mean)
    scale = Decimal(2**_BITS)
    probability = context.exp(context.minus(lam))
    cumulative = probability
    # Up to where every draw is covered (the last threshold: all of 2⁶⁴), or far enough into the tail
    # that what is left is below 2⁻⁶⁴ for any mean; the draws beyond either go to the last count.
    last = int(mean + 20.0 * mean**0.5 + 20.0)
    thresholds: list[int] = []
    for k in range(last + 1):
        if k:
            probability = context.divide(context.multiply(probability, lam), k)
            cumulative = context.add(cumulative, probability)
        threshold = int(context.multiply(cumulative, scale).to_integral_value(rounding=ROUND_FLOOR))
        if threshold >= 2**_BITS - 1 or k == last:
            thresholds.append(2**_BITS)
            break
        thresholds.append(threshold)
    return tuple(thresholds)


def _below(generator: random.Random, n: int) -> int:
    """A uniform integer in ``[0, n)`` from whole bit draws (rejection), the same on every Python."""
    bits = n.bit_length()
    drawn = generator.getrandbits(bits)
    while drawn >= n:
        drawn = generator.getrandbits(bits)
    return drawn


def _integer_weights(weights: list[float]) -> list[int]:
    """The float weights as integers in exactly the same ratios (floats are dyadic fractions)."""
    fractions = [Fraction(weight) for weight in weights]
    denominator = lcm(*(f.denominator for f in fractions))
    integers = [int(f * denominator) for f in fractions]
    common = gcd(*integers)
    return [i // common for i in integers] if common > 1 else integers


class _Candidates:
    """The segments one stop draw picks from: ascending, each once, with integer weights."""

    __slots__ = ("segments", "weights")

    def __init__(self, draw: StopDraw, stations: Mapping[str, tuple[Station, ...]]) -> None:
        weight_of: dict[int, float] = {}
        for name in draw.stations:
            if name not in stations:
                known = ", ".join(sorted(stations)) or "none"
                msg = f"station set {name!r} is not known (sets: {known})"
                raise ValueError(msg)
            for station in stations[name]:
                weight_of.setdefault(station.segment, station.weight)
        segments = sorted(weight_of)
        weights = _integer_weights([weight_of[s] for s in segments]) if draw.weighted else [1] * len(segments)
        kept = [(s, w) for s, w in zip(segments, weights, strict=True) if w > 0]
        if not kept:
            msg = f"station sets {list(draw.stations)!r} hold no segment to draw a stop from"
            raise ValueError(msg)
        self.segments = tuple(s for s, _ in kept)
        self.weights = tuple(w for _, w in kept)

    def draw(self, generator: random.Random, previous: int | None) -> int:
        pairs = list(zip(self.segments, self.weights, strict=True))
        if previous is not None and len(pairs) > 1 and previous in self.segments:
            pairs = [pair for pair in pairs if pair[0] != previous]
        if len(pairs) == 1:
            return pairs[0][0]
        pick = _below(generator, sum(w for _, w in pairs))
        for segment, weight in pairs:
            if pick < weight:
                return segment
            pick -= weight
        raise AssertionError(pick)  # unreachable: pick < the total of the weights


def _ms(seconds: float | None) -> int | None:
    return None if seconds is None else round(seconds * 1000)


def _order_record(order: Order) -> list[Any]:
    """An orders.csv order in canonical, integer form: times and dwells in ms."""
    stops = [[s.segment, None if s.progress is None else s.progress.value, _ms(s.dwell)] for s in order.stops]
    types = None if order.vehicle_types is None else list(order.vehicle_types)
    return [order.id, _ms(order.release), _ms(order.deadline), stops, types, order.priority]


class OrderSource:
    """The orders a run releases, step by step (see the module's description).

    Args:
        orders: The ``orders.csv`` orders, in release order.
        stream: The order stream to generate, or ``None``.
        stations: The station sets by name (the stream's stops are drawn from them).
        time_step: Seconds per step.
        pool: Release ``orders`` as a closed pool of this many open orders (see the module), or ``None``:
            each at its ``release``.

    Raises ``ValueError`` for a stream the loader should have refused (a set that names no station, a
    rate, interval or pool size that is not positive, no stop at all) and for an ``orders.csv`` id of the
    form generated ids take (``s1``, ``s2``, ...) beside a stream.
    """

    def __init__(
        self,
        orders: tuple[Order, ...],
        stream: OrderStream | None,
        stations: Mapping[str, tuple[Station, ...]],
        time_step: float,
        pool: int | None = None,
    ) -> None:
        if not time_step > 0.0:
            msg = f"time_step={time_step!r} must be > 0"
            raise ValueError(msg)
        if pool is not None and not pool >= 1:
            msg = f"pool={pool!r} must be at least 1"
            raise ValueError(msg)
        self._dt = time_step
        self._pool = pool
        # Stably by release: rows come in release order; this only guards orders made in code. (A pool
        # releases them in file order.)
        self._orders = tuple(orders) if pool is not None else tuple(sorted(orders, key=lambda o: o.release))
        self._next_order = 0
        # The step each orders.csv order is released at: the first whose start is >= release - 1e-9.
        self._order_steps = tuple(self._first_step_at(o.release) for o in self._orders)
        self._pool_credit = pool or 0  # a pool: orders to release at the next step asked for
        self._pool_open: set[str] = set()  # a pool: its orders released and not completed
        self._stream = stream
        self._asked = -1  # the last step asked about
        self._made = 0  # generated orders so far
        self._open: set[str] = set()  # generated orders released and not completed
        self._refills = 0  # pool: completions not yet replaced
        self._stream_done = stream is None
        if stream is not None:
            self._check(stream)
            self._candidates = tuple(_Candidates(draw, stations) for draw in stream.stops)
            self._arrivals = random.Random(f"fleetsim-orders/{stream.seed}/arrivals")
            self._contents = random.Random(f"fleetsim-orders/{stream.seed}/contents")
            arrivals = stream.arrivals
            self._thresholds: tuple[int, ...] = ()
            if arrivals.process == "poisson":
                assert arrivals.rate is not None  # _check
                self._thresholds = poisson_thresholds(arrivals.rate / 3600.0 * time_step)
            self._start_step = self._first_step_at(arrivals.start)
            self._due_count = 0  # interval: orders due so far
            if stream.limit is not None and stream.limit <= 0:
                self._stream_done = True
            for order in self._orders:
                if _GENERATED.fullmatch(order.id):
                    where = f" (orders.csv line {order.line})" if order.line is not None else ""
                    msg = (
                        f"order_id={order.id!r}{where} has the form of a generated order's id (s1, s2, ...): "
                        "rename it, the order stream names its orders so"
                    )
                    raise ValueError(msg)

    @staticmethod
    def _check(stream: OrderStream) -> None:
        arrivals = stream.arrivals
        value = {"poisson": arrivals.rate, "interval": arrivals.interval, "pool": arrivals.open}.get(arrivals.process)
        name = {"poisson": "rate", "interval": "interval", "pool": "open"}.get(arrivals.process)
        if name is None:
            msg = f"arrivals process={arrivals.process!r} must be poisson, interval or pool"
            raise ValueError(msg)
        if value is None or not value > 0:
            msg = f"{arrivals.process} arrivals: {name}={value!r} must be > 0"
            raise ValueError(msg)
        if sum(draw.count[0] for draw in stream.stops) < 1:
            msg = f"stops={stream.stops!r} must give every order at least one stop"
            raise ValueError(msg)

    def _first_step_at(self, time: float) -> int:
        """The first step whose start ``k × time_step`` is at or after ``time`` (less 1e-9)."""
        dt = self._dt
        step = max(0, int((time - _EPS) / dt))
        while step > 0 and (step - 1) * dt >= time - _EPS:
            step -= 1
        while step * dt < time - _EPS:
            step += 1
        return step

    # -- the loop's calls ---------------------------------------------------------------------------

    def due(self, step: int) -> list[Order]:
        """The orders released at the start of step ``step``, in release order (``orders.csv`` ones first).

        Asked for steps 0, 1, 2, ... once each; a step left out releases its orders at the next one asked.
        """
        if step <= self._asked:
            msg = f"step={step!r} was already asked for (the last was {self._asked})"
            raise ValueError(msg)
        released: list[Order] = []
        if self._pool is not None:
            while self._pool_credit and self._next_order < len(self._orders):
                order = self._orders[self._next_order]
                released.append(order)
                self._pool_open.add(order.id)
                self._next_order += 1
                self._pool_credit -= 1
        while (
            self._pool is None and self._next_order < len(self._orders) and self._order_steps[self._next_order] <= step
        ):
            released.append(self._orders[self._next_order])
            self._next_order += 1
        if not self._stream_done:
            for missed in range(self._asked + 1, step):  # only when steps were left out
                self._generate(missed, step, released)
            self._generate(step, step, released)
        self._asked = step
        return released

    def completed(self, order_id: str) -> None:
        """``order_id`` was completed: a closed pool releases another at the next step's start."""
        if order_id in self._pool_open:
            self._pool_open.discard(order_id)
            self._pool_credit += 1
            return
        if order_id not in self._open:
            if _GENERATED.fullmatch(order_id) and self._stream is not None and int(order_id[1:]) <= self._made:
                msg = f"order {order_id!r} was already completed"
                raise ValueError(msg)
            return  # an orders.csv order
        self._open.discard(order_id)
        if self._stream is not None and self._stream.arrivals.process == "pool" and not self._stream_done:
            self._refills += 1

    def exhausted(self) -> bool:
        """Whether no order will ever be released again."""
        return self._next_order == len(self._orders) and self._stream_done

    def header(self) -> dict[str, Any]:
        """What decides the run's orders, canonical and in integers (ms, thousandths), for the trace header:
        ``orders`` (each ``orders.csv`` order), ``order_pool`` (only when they are released as a pool) and
        ``stream`` (the stream and the stations it draws from). Empty without any."""
        header: dict[str, Any] = {}
        if self._orders:
            header["orders"] = [_order_record(order) for order in self._orders]
        if self._pool is not None:
            header["order_pool"] = self._pool
        stream = self._stream
        if stream is not None:
            arrivals = stream.arrivals
            header["stream"] = {
                "seed": stream.seed,
                "process": arrivals.process,
                "rate_milli_per_hour": None if arrivals.rate is None else round(arrivals.rate * 1000),
                "interval_ms": _ms(arrivals.interval),
                "open": arrivals.open,
                "start_ms": _ms(arrivals.start),
                "until_ms": _ms(arrivals.until),
                "stops": [
                    {
                        "stations": list(draw.stations),
                        "weighted": draw.weighted,
                        "dwell_ms": [_ms(draw.dwell[0]), _ms(draw.dwell[1])],
                        "count": list(draw.count),
                        "progress": None if draw.progress is None else draw.progress.value,
                        # The segments drawn from and the exact integer weights the draws use.
                        "segments": [[s, w] for s, w in zip(candidates.segments, candidates.weights, strict=True)],
                    }
                    for draw, candidates in zip(stream.stops, self._candidates, strict=True)
                ],
                "deadline_ms": _ms(stream.deadline),
                "vehicle_types": None if stream.vehicle_types is None else list(stream.vehicle_types),
                "priority": stream.priority,
                "limit": stream.limit,
            }
        return header

    # -- generation ---------------------------------------------------------------------------------

    def _generate(self, step: int, release_step: int, released: list[Order]) -> None:
        """Step ``step``'s generated orders, released at ``release_step``'s start."""
        stream = self._stream
        assert stream is not None
        arrivals = stream.arrivals
        now = step * self._dt
        if step < self._start_step:
            return
        if arrivals.until is not None and now > arrivals.until + _EPS:
            self._stream_done = True
            return
        if arrivals.process == "poisson":
            count = bisect_right(self._thresholds, self._arrivals.getrandbits(_BITS))
        elif arrivals.process == "interval":
            assert arrivals.interval is not None
            count = 0
            while arrivals.start + self._due_count * arrivals.interval <= now + _EPS:
                self._due_count += 1
                count += 1
        else:
            assert arrivals.open is not None
            count = arrivals.open if step == self._start_step else 0
            count, self._refills = count + self._refills, 0
        if stream.limit is not None:
            count = min(count, stream.limit - self._made)
        for _ in range(count):
            released.append(self._make(release_step * self._dt))
        if stream.limit is not None and self._made >= stream.limit:
            self._stream_done = True
        elif arrivals.until is not None:
            following = (step + 1) * self._dt
            if arrivals.process == "interval":
                assert arrivals.interval is not None
                following = max(following, arrivals.start + self._due_count * arrivals.interval)
            if following > arrivals.until + _EPS:
                self._stream_done = True

    def _make(self, release: float) -> Order:
        stream = self._stream
        assert stream is not None
        contents = self._contents
        stops: list[Stop] = []
        previous: int | None = None
        for draw, candidates in zip(stream.stops, self._candidates, strict=True):
            low, high = draw.count
            count = low if low == high else low + _below(contents, high - low + 1)
            for _ in range(count):
                segment = candidates.draw(contents, previous)
                low_dwell, high_dwell = draw.dwell
                dwell = low_dwell
                if high_dwell != low_dwell:
                    dwell = round(low_dwell + (high_dwell - low_dwell) * contents.getrandbits(32) / 2**32, 3)
                stops.append(Stop(segment, draw.progress, dwell))
                previous = segment
        self._made += 1
        order_id = f"s{self._made}"
        self._open.add(order_id)
        deadline = None if stream.deadline is None else release + stream.deadline
        return Order(order_id, tuple(stops), release, deadline, stream.vehicle_types, stream.priority)
