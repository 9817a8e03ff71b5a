"""The code of docs/python.md runs: its python blocks, except those marked `# not run`,
concatenated into one script and run in a fresh interpreter in a temporary directory."""

import os
import pathlib
import re
import subprocess
import sys

DOC = pathlib.Path(__file__).resolve().parents[3] / "docs" / "python.md"


def runnable_blocks(text):
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    return [b for b in blocks if not b.lstrip().startswith("# not run")]


def test_tour_runs(mni_path, tmp_path):
    blocks = runnable_blocks(DOC.read_text())
    assert len(blocks) >= 5
    script = tmp_path / "tour.py"
    script.write_text("\n".join(blocks))
    env = dict(os.environ, GLINT_DATA=str(mni_path.parents[1]))
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "superior.png").stat().st_size > 1000
    assert (tmp_path / "brain.json").is_file()
