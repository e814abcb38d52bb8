"""MovingAI grid maps (``*.map``) as lane graphs, and MovingAI scenario files (``*.scen``) as vehicles
and tasks."""
