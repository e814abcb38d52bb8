"""Gating planner changes in CI: recorded trace hashes (lock files) and metric baselines."""
