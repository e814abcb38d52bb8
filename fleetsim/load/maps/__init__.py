"""A site map in any format: choosing the reader by the file (Tiled, LIF, Open-RMF) and converting
between formats."""
