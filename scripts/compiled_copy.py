"""Build fleetsim's optional compiled build in a copy of this tree: ``python -m scripts.compiled_copy DEST``.

The copy holds this tree's files as they are now (git's tracked and untracked files, none it ignores),
with the modules of ``fleetsim/compiled.py`` compiled by mypyc beside their sources
(``FLEETSIM_COMPILE=1 setup.py build_ext --inplace``). Python imports an extension module before a
``.py`` file of the same name, so ``PYTHONPATH=DEST`` runs the compiled build while the installed
fleetsim stays pure Python. The comparison benchmarks (``benchmarks/compare.py --compiled``) and the
compiled build's test (``tests/integration/test_compiled_build.py``) build it this way.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

__all__ = ["build_compiled_copy", "is_compiled_copy_of"]

HERE = Path(__file__).resolve().parent.parent


def _files(tree: Path) -> list[str]:
    listed = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
        cwd=tree,
        capture_output=True,
        check=True,
    )
    return sorted(name for name in listed.stdout.decode().split("\0") if name and (tree / name).is_file())


def build_compiled_copy(dest: Path, tree: Path = HERE) -> Path:
    """Copy ``tree`` to ``dest`` (which must not exist) and compile the hot paths there; returns ``dest``.
    Raises :class:`RuntimeError` with the compiler's output when the build fails."""
    for name in _files(tree):
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(tree / name, target)
    env = {**os.environ, "FLEETSIM_COMPILE": "1"}
    built = subprocess.run(
        [sys.executable, "setup.py", "-q", "build_ext", "--inplace"],
        cwd=dest,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if built.returncode != 0:
        raise RuntimeError(f"the compiled build in {dest} failed:\n{built.stdout[-4000:]}\n{built.stderr[-4000:]}")
    shutil.rmtree(dest / "build", ignore_errors=True)  # mypyc's C sources and object files
    return dest


def is_compiled_copy_of(dest: Path, tree: Path = HERE) -> bool:
    """Whether ``dest`` is a compiled build of ``tree`` as it is now: every file the same, and every module
    of ``fleetsim/compiled.py`` compiled beside its source."""
    names = _files(tree)
    if any(not (dest / name).is_file() or (dest / name).read_bytes() != (tree / name).read_bytes() for name in names):
        return False
    listed = subprocess.run(
        [
            sys.executable,
            "-c",
            "from fleetsim.compiled import *; print(len(compiled_modules()) == len(COMPILED_MODULES))",
        ],
        cwd=dest,
        env={**os.environ, "PYTHONPATH": str(dest)},
        capture_output=True,
        text=True,
        check=False,
    )
    return listed.stdout.strip() == "True"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dest", type=Path, help="a folder that does not exist yet")
    args = parser.parse_args()
    if args.dest.exists():
        parser.error(f"{args.dest} exists; name a new folder")
    try:
        build_compiled_copy(args.dest)
    except RuntimeError as error:
        print(error, file=sys.stderr)
        return 1
    print(f"compiled build in {args.dest}: run it with PYTHONPATH={args.dest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
