"""What every loader shares: reading text files, collecting every error of a file before raising,
locating values in JSON and YAML documents, "did you mean" hints, and a site map's options and notes."""
