"""The ``vda5050:`` planner spec: the scenario's vehicles as VDA 5050 vehicles, driven by a master control.

    vda5050:                                   defaults: VDA 5050 2.0, an embedded broker, real time
    vda5050:version=2.1,speed=10               2.1, ten times real time
    vda5050:broker=mqtt://user:secret@host:1883,interface=uagv,manufacturer=acme
    vda5050:speed=10,exec=python master.py     and start the master control as a child process

Options, comma-separated ``key=value``: ``version`` (2.0 or 2.1), ``speed`` (times real time, > 0),
``broker`` (``mqtt://`` or ``mqtts://``; default: an embedded broker on a free loopback port),
``interface`` and ``manufacturer`` (the topic's ``interfaceName`` and ``manufacturer``),
``state_interval`` (simulated seconds between states when nothing changes), ``exec`` (last: the rest of
the spec is the master control's command line, started once the broker is up, with the broker's address
and the topic names in its environment: see :data:`ENVIRONMENT`).
"""

from __future__ import annotations

import functools
from dataclasses import replace

from fleetsim.specs.python import PlannerFactory, PlannerSpecError, command_words
from fleetsim.vda5050.broker import BrokerError, check_reachable, parse_broker_url
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings
from fleetsim.vda5050.model import VERSIONS

__all__ = ["ENVIRONMENT", "VDA5050_PREFIX", "vda5050_factory"]

VDA5050_PREFIX = "vda5050:"
# What a master control started with ``exec=`` finds in its environment.
ENVIRONMENT = {
    "FLEETSIM_MQTT_URL": "the broker, mqtt://host:port (no password: see FLEETSIM_MQTT_USERNAME/PASSWORD)",
    "FLEETSIM_MQTT_USERNAME": "the broker's user name, when it has one",
    "FLEETSIM_MQTT_PASSWORD": "the broker's password, when it has one",
    "FLEETSIM_VDA5050_INTERFACE": "the topics' interfaceName",
    "FLEETSIM_VDA5050_MANUFACTURER": "the vehicles' manufacturer",
    "FLEETSIM_VDA5050_VERSION": "the protocol version the vehicles speak (2.0.0 or 2.1.0)",
}
_KEYS = ("version", "speed", "broker", "interface", "manufacturer", "state_interval", "exec")


def vda5050_factory(spec: str) -> PlannerFactory:
    """The factory of fresh :class:`Vda5050Fleet` planners that ``spec`` describes (see the module
    docstring); every mistake is a :class:`PlannerSpecError` naming the option and the value."""
    settings, command = _parse(spec)
    if settings.broker is not None:  # an unreachable broker is the user's mistake: said before any run
        try:
            check_reachable(settings.broker, timeout=5.0)
        except BrokerError as error:
            raise PlannerSpecError(f"planner spec {spec!r}: {error}", spec) from None
    return PlannerFactory(spec, functools.partial(Vda5050Fleet, settings, master_command=command))


def _parse(spec: str) -> tuple[Vda5050Settings, tuple[str, ...] | None]:
    settings = Vda5050Settings()
    rest = spec[len(VDA5050_PREFIX) :]
    command: tuple[str, ...] | None = None
    if "exec=" in rest:
        rest, _, tail = rest.partition("exec=")
        rest = rest.rstrip(",")
        command = _command(spec, tail)
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, equals, value = item.partition("=")
        if not equals or key not in _KEYS:
            known = ", ".join(_KEYS)
            msg = f"planner spec {spec!r}: {item!r} is not an option; write key=value with key one of {known}"
            raise PlannerSpecError(msg, spec)
        settings = _set(spec, settings, key, value)
    return settings, command


def _set(spec: str, settings: Vda5050Settings, key: str, value: str) -> Vda5050Settings:
    if key == "version":
        if value not in VERSIONS:
            msg = f"planner spec {spec!r}: version={value!r}; fleetsim's vehicles speak {' or '.join(VERSIONS)}"
            raise PlannerSpecError(msg, spec)
        return replace(settings, version=value)
    if key in ("speed", "state_interval"):
        try:
            number = float(value)
        except ValueError:
            number = float("nan")
        if not number > 0 or number == float("inf"):
            msg = f"planner spec {spec!r}: {key}={value!r} must be a number > 0"
            raise PlannerSpecError(msg, spec)
        return replace(settings, speed=number) if key == "speed" else replace(settings, state_interval=number)
    if key == "broker":
        try:
            return replace(settings, broker=parse_broker_url(value))
        except BrokerError as error:
            raise PlannerSpecError(f"planner spec {spec!r}: {error}", spec) from None
    if not value or "/" in value or "+" in value or "#" in value:
        msg = f"planner spec {spec!r}: {key}={value!r} must be a non-empty topic level (no '/', '+' or '#')"
        raise PlannerSpecError(msg, spec)
    if key == "interface":
        return replace(settings, interface_name=value)
    return replace(settings, manufacturer=value)


def _command(spec: str, text: str) -> tuple[str, ...]:
    empty = f"planner spec {spec!r}: exec= names no command; write exec=COMMAND, e.g. 'exec=python master.py'"
    return command_words(spec, text, whose="the master control's", empty=empty)
