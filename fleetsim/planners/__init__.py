"""Reference planners: ``fleetsim.planners:ReservingPlanner`` (conflict-free, finishes what is solvable),
``fleetsim.planners:BFSPlanner`` (the thesis's, collides on purpose) and
``fleetsim.planners:GreedyPlanner`` (safe, no coordination: gets stuck on purpose)."""

from fleetsim.planners.bfs import BFSPlanner
from fleetsim.planners.greedy import GreedyPlanner
from fleetsim.planners.reserving import ReservingPlanner

__all__ = ["BFSPlanner", "GreedyPlanner", "ReservingPlanner"]
