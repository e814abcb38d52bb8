"""Maintenance commands run from the repository's root (`python -m scripts.gen_docs`); not shipped."""
