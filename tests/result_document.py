"""What every test of a run's JSON document expects it to hold (SPEC §10), in one place."""

RESULT_KEYS = frozenset(
    {
        "scenario",
        "planner",
        "status",
        "failures",
        "trace_hash",
        "sim_time",
        "steps",
        "tasks",
        "rejections",
        "collisions",
        "metrics",
        "artifacts",
    }
)
