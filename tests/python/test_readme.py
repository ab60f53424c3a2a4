# SPDX-License-Identifier: MIT
"""The README's Python examples run as written."""
import os
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def run_readme_block(marker):
    """Runs the README's bash block after `<!-- marker -->` (a python3 heredoc); its stdout."""
    readme = (SOURCE_DIR / "README.md").read_text()
    block = re.search(rf"<!-- {marker} -->\n```bash\n(.*?)```", readme, re.S).group(1)
    lines = block.splitlines()
    assert lines[0] == "PYTHONPATH=build/python python3 - <<'EOF'" and lines[-1] == "EOF"
    code = "\n".join(lines[1:-1])
    # This build's package (ctest's PYTHONPATH) instead of build/python under the source tree.
    process = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=os.environ, cwd=SOURCE_DIR)
    assert process.returncode == 0, process.stderr
    return process.stdout


def test_readme_python_example_runs():
    shape, energy, seconds = re.match(r"\((\d+), 3\) (\S+) (\S+)",
                                      run_readme_block("python example")).groups()
    assert float(energy) > 0 and float(seconds) > 0


def test_readme_session_example_runs():
    frames = [re.fullmatch(r"(\S+) (\S+) (\S+) s", line).groups()
              for line in run_readme_block("python session example").splitlines()]
    assert [t for t, _, _ in frames] == [f"{0.1 * k:.1f}" for k in range(1, 11)]
    energies = [float(energy) for _, energy, _ in frames]
    assert energies == sorted(energies) and energies[0] > 0  # dragged further each frame
