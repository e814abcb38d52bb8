"""League of Robot Runners problems (a JSON problem file naming a MovingAI-style map, an agent file and a
task file) as scenarios: robots as vehicles, tasks as transport orders released as the competition's
closed pool, its horizon as a shift, its 2026 delays as random stops (docs/lorr.md)."""
