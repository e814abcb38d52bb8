"""Scenario CSV files (SPEC §5): a located CSV table reader, and ``vehicles.csv`` and ``tasks.csv``."""
