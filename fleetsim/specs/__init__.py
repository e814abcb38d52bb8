"""Planner specs: how a command line, a suite or pytest names the planner to run.

``module:attr`` (a Python planner class or factory) is read by ``fleetsim.specs.python``; ``exec:COMMAND``
by ``fleetsim.exec.spec`` and ``vda5050:...`` by ``fleetsim.vda5050.spec``, both building on it.
"""
