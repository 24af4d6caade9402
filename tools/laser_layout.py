#!/usr/bin/env python3
"""Code layout of laser/: files above 600 lines and function bodies above 80 lines.

  python3 tools/laser_layout.py [--max-file 600] [--max-function 80] [DIR]

The check of tools/code_layout.py (function detection described there) on laser/ alone.
Exit status 1 when anything is above a limit.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import code_layout  # noqa: E402

if __name__ == "__main__":
    if not any(not a.startswith("-") and not a.isdigit() for a in sys.argv[1:]):
        sys.argv.append(os.path.join(code_layout.TOP, "laser"))
    sys.exit(code_layout.main())
