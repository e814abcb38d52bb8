"""fleetsim's vehicles as VDA 5050 vehicles on an MQTT broker, so a VDA 5050 master control (a fleet
manager) is tested as any planner is: its orders are validated against the map and become the vehicles'
plans (released nodes and edges fixed legs, the horizon planned ones), and the run is judged as any run.

The map as nodes and edges: :mod:`.places`; the messages: :mod:`.model` and :mod:`.messages`; the broker
and the MQTT link: :mod:`.broker` and :mod:`.link`. Needs the ``vda5050`` extra (paho-mqtt, amqtt).
"""
