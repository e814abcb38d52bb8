"""Open-RMF building maps (``*.building.yaml``): lanes of a level as segments."""
