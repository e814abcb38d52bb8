"""Planners in other processes and languages: the JSON-lines protocol (``--planner exec:COMMAND``)."""

from fleetsim.exec.process import PlannerProcessError, SubprocessPlanner

__all__ = ["PlannerProcessError", "SubprocessPlanner"]
