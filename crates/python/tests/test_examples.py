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
            assert np.asarray(im).max() > 0  # something was drawn
    errors = [l for l in proc.stderr.splitlines() if "broken.nii" in l]
    assert len(errors) == 1, proc.stderr
    assert "2 of 3 rendered" in proc.stderr
