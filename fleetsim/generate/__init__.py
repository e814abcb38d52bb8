"""Generated sites: ``fleetsim generate warehouse`` writes a ready-to-run warehouse scenario folder.

[`generate_warehouse`][fleetsim.generate.generate_warehouse] is the Python side of the command; the layout
itself is [`warehouse_layout`][fleetsim.generate.warehouse_layout.warehouse_layout].
"""

from __future__ import annotations

from fleetsim.generate.options import GenerateError, WarehouseOptions
from fleetsim.generate.warehouse import GeneratedWarehouse, generate_warehouse

__all__ = ["GenerateError", "GeneratedWarehouse", "WarehouseOptions", "generate_warehouse"]
