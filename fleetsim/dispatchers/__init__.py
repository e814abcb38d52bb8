"""Reference dispatchers: ``fleetsim.dispatchers:NearestVehicleDispatcher`` (the thesis's scheduler: the
idle vehicle with the least travel time to the order's first stop) and
``fleetsim.dispatchers:OldestFirstDispatcher`` (oldest order first, whatever the distance)."""

from fleetsim.dispatchers.nearest import NearestVehicleDispatcher
from fleetsim.dispatchers.oldest import OldestFirstDispatcher

__all__ = ["NearestVehicleDispatcher", "OldestFirstDispatcher"]
