"""Suites (SPEC §13) and whole scenarios: the suite file and its schema, disturbances, and a scenario
assembled from its map, CSV files and suite settings."""
