#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Runs one pytest file for ctest (python/CMakeLists.txt); exits 77 (ctest: skipped) with a
message when numpy or pytest is missing, so the suite skips cleanly without them."""
import sys

for module in ("numpy", "pytest"):
    try:
        __import__(module)
    except ImportError:
        print(f"skipped: the Python module {module} is not installed for {sys.executable} "
              f"(Debian: python3-{module})")
        sys.exit(77)

import pytest  # noqa: E402

# -p no:cacheprovider: no .pytest_cache in the source tree.
sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", *sys.argv[1:]]))
