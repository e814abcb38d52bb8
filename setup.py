"""The optional compiled build: ``FLEETSIM_COMPILE=1`` compiles fleetsim's hot paths with mypyc.

Everything else about the package is in pyproject.toml. Without the variable this file adds nothing and
fleetsim installs as pure Python. With it, the modules listed in ``fleetsim/compiled.py`` are compiled to
C extension modules from the same source (mypyc, which comes with mypy, and a C compiler are needed; pip
needs ``--no-build-isolation`` to use the mypy installed beside it):

    pip install mypy==2.4.1 setuptools wheel
    FLEETSIM_COMPILE=1 pip install --no-build-isolation .

docs/performance.md, "The compiled build", says what it gains and how it is tested.
"""

from __future__ import annotations

import ast
import os
import sys
from pathlib import Path
from typing import Any

from setuptools import setup

HERE = Path(__file__).resolve().parent


def listed_modules() -> list[str]:
    """COMPILED_MODULES from fleetsim/compiled.py, read without importing fleetsim."""
    source = HERE / "fleetsim" / "compiled.py"
    for node in ast.parse(source.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and [getattr(t, "id", None) for t in node.targets] == ["COMPILED_MODULES"]:
            return list(ast.literal_eval(node.value))
    raise SystemExit(f"{source}: no COMPILED_MODULES tuple")


def extensions() -> list[Any]:
    if os.environ.get("FLEETSIM_COMPILE", "") in ("", "0"):
        return []
    if "editable_wheel" in sys.argv:
        raise SystemExit(
            "FLEETSIM_COMPILE=1 does not make an editable install: the compiled modules would be imported instead "
            "of the sources you edit. Install without -e, or build a compiled copy of the checkout with "
            "python -m scripts.compiled_copy DEST and run it with PYTHONPATH=DEST"
        )
    try:
        from mypyc.build import mypycify
    except ImportError:
        raise SystemExit(
            "FLEETSIM_COMPILE=1 needs mypyc, which comes with mypy: pip install mypy==2.4.1, then build with "
            "pip install --no-build-isolation"
        ) from None
    paths = [str(Path(*name.split(".")).with_suffix(".py")) for name in listed_modules()]
    built = list(mypycify(paths, opt_level=os.environ.get("MYPYC_OPT_LEVEL", "3")))
    for extension in built:
        # The same floating-point results as the interpreter, operation by operation: never fuse a
        # multiplication and an addition into one rounding (GCC does by default where the processor has
        # fused multiply-add, as on ARM), or a trace hash could differ from the pure-Python build's.
        extension.extra_compile_args = [*extension.extra_compile_args, "-ffp-contract=off"]
    return built


setup(ext_modules=extensions())
