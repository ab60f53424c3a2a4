# SPDX-License-Identifier: MIT
"""The README's Python example runs as written."""
import os
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def test_readme_python_example_runs():
    readme = (SOURCE_DIR / "README.md").read_text()
    block = re.search(r"<!-- python example -->\n```bash\n(.*?)```", readme, re.S).group(1)
    lines = block.splitlines()
    assert lines[0] == "PYTHONPATH=build/python python3 - <<'EOF'" and lines[-1] == "EOF"
    code = "\n".join(lines[1:-1])
    # This build's package (ctest's PYTHONPATH) instead of build/python under the source tree.
    process = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=os.environ, cwd=SOURCE_DIR)
    assert process.returncode == 0, process.stderr
    shape, energy, seconds = re.match(r"\((\d+), 3\) (\S+) (\S+)", process.stdout).groups()
    assert float(energy) > 0 and float(seconds) > 0
