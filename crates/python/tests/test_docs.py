"""The code of docs/python.md runs: its python blocks, except those marked `# not run`,
concatenated into one script and run in a fresh interpreter in a temporary directory."""

import json
import os
import pathlib
import re
import subprocess
import sys

import numpy as np
from PIL import Image as PILImage

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
    # superior.png: the tour's 256x256 scene from above, the brain in the middle of a
    # black background; brain.json: the scene that renders it again.
    with PILImage.open(tmp_path / "superior.png") as im:
        assert im.size == (256, 256) and im.mode == "RGB"
        px = np.asarray(im)
    lit = px.max(axis=2) > 10
    assert 0.2 < lit.mean() < 0.9, lit.mean()
    assert lit[96:160, 96:160].mean() > 0.9  # the brain fills the centre
    assert not lit[0, :].any() and not lit[-1, :].any()  # margins are background
    scene = json.loads((tmp_path / "brain.json").read_text())
    assert scene["preset"] == "mr-t2-brain" and scene["size"] == [256, 256], scene
