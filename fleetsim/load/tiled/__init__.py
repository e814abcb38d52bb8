"""Tiled maps (SPEC §3), parsed by hand: the map header, object templates, the reader and the writer."""
