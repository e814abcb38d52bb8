"""Motion (SPEC §8): how a vehicle's speed and distance evolve along its fixed legs."""

from fleetsim.motion.profile import SpeedProfile

__all__ = ["SpeedProfile"]
