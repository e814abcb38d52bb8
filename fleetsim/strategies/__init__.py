"""Hypothesis strategies for valid layouts and whole scenarios, and saving one as a scenario folder.

Generated scenarios hunt for planner bugs no one thought to draw; a failing one shrinks toward a small
layout with few vehicles and tasks and is kept as an ordinary scenario folder (:func:`save_scenario`).
Layout geometry without Hypothesis lives in :mod:`fleetsim.strategies.geometry`.
"""

from fleetsim.strategies._files import load_saved, save_scenario
from fleetsim.strategies._layouts import LAYOUT_KINDS, layouts
from fleetsim.strategies._room import NoRoomError
from fleetsim.strategies._scenarios import GenerationSpec, scenarios

__all__ = ["LAYOUT_KINDS", "GenerationSpec", "NoRoomError", "layouts", "load_saved", "save_scenario", "scenarios"]
