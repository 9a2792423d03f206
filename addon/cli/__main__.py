"""`python -m addon.cli render FILE.blend --out OUT.exr …` (addon/cli/command.py)."""

import sys

from .command import module_main

raise SystemExit(module_main(sys.argv[1:]))
