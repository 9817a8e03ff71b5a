"""examples/python/thumbnails.py on a small directory of scans, one of them corrupt."""

import pathlib
import subprocess
import sys

import nibabel as nib
import numpy as np
from PIL import Image as PILImage

EXAMPLE = pathlib.Path(__file__).resolve().parents[3] / "examples" / "python" / "thumbnails.py"


def test_thumbnails(mni_path, tmp_path):
    scans = tmp_path / "scans"
    (scans / "sub-01").mkdir(parents=True)
    (scans / "sub-01" / "t1.nii.gz").symlink_to(mni_path)
    ball = np.fromfunction(lambda i, j, k: 1000.0 * ((i - 16) ** 2 + (j - 16) ** 2 + (k - 16) ** 2 < 100), (32, 32, 32))
    nib.save(nib.Nifti1Image(ball.astype(np.int16), np.diag([2.0, 2.0, 2.0, 1.0])), str(scans / "ball.nii"))
    (scans / "broken.nii").write_bytes(b"not a nifti file" * 10)
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, str(EXAMPLE), str(scans), str(out), "--size", "48", "--workers", "2"],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 1, proc.stderr  # the broken scan
    pngs = sorted(p.name for p in out.iterdir())
    assert pngs == ["ball.png", "sub-01__t1.png"]
    for name in pngs:
        with PILImage.open(out / name) as im:
            assert im.size == (48, 48) and im.mode == "RGB"
            lit = np.asarray(im).max(axis=2) > 10
        # The object is in the middle of the thumbnail, the corners are background, and
        # it covers a plausible share: the ball a disc (radius 10 of a 32-voxel box, so
        # about pi (10/32)^2 = 0.31 of the frame when the box fills it), the brain more.
        assert lit[20:28, 20:28].all(), name
        assert not (lit[0, 0] or lit[0, -1] or lit[-1, 0] or lit[-1, -1]), name
        assert 0.15 < lit.mean() < 0.9, (name, lit.mean())
    errors = [l for l in proc.stderr.splitlines() if "broken.nii" in l]
    assert len(errors) == 1, proc.stderr
    assert "2 of 3 rendered" in proc.stderr
