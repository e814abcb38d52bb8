"""fleetsim's vehicles as VDA 5050 vehicles on an MQTT broker, so a VDA 5050 master control (a fleet
manager) is tested as any planner is: its orders are validated against the map and become the vehicles'
plans (released nodes and edges fixed legs, the horizon planned ones), and the run is judged as any run.

The map as nodes and edges: :mod:`.places`; the messages: :mod:`.model` and :mod:`.messages`; the broker
and the MQTT link: :mod:`.broker` and :mod:`.link`; the vehicles as a planner: :mod:`.fleet`, named by a
``vda5050:`` planner spec (:mod:`.spec`); a master control the spec starts: :mod:`.master`. Needs the ``vda5050`` extra (paho-mqtt, amqtt); this package's
own module imports neither, so a spec without the extra gets a clear error.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from fleetsim.specs.python import PlannerFactory

__all__ = ["load_vda5050_factory"]


def load_vda5050_factory(spec: str) -> PlannerFactory:
    """The factory a ``vda5050:`` planner spec names (:mod:`fleetsim.vda5050.spec`); without the
    ``vda5050`` extra installed, a :class:`~fleetsim.specs.python.PlannerSpecError` saying so."""
    from fleetsim.specs.python import PlannerSpecError

    try:
        from fleetsim.vda5050.spec import vda5050_factory
    except ImportError as error:
        msg = (
            f"planner spec {spec!r} needs fleetsim's vda5050 extra (an MQTT client and broker): "
            f"pip install 'fleetsim[vda5050]' ({error})"
        )
        raise PlannerSpecError(msg, spec) from None
    return vda5050_factory(spec)
