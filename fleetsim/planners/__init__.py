"""Reference planners: ``fleetsim.planners:BFSPlanner`` (the thesis's, collides on purpose) and
``fleetsim.planners:ReservingPlanner`` (conflict-free)."""

from fleetsim.planners.bfs import BFSPlanner
from fleetsim.planners.reserving import ReservingPlanner

__all__ = ["BFSPlanner", "ReservingPlanner"]
