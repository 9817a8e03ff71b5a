#!/usr/bin/env python3
"""JPEG-LS codestreams encoded and decoded by CharLS, for glint's own JPEG-LS decoder
(crates/io/src/dicom/jpegls.rs, whose tests read them from crates/io/tests/data/jpegls/).

Each case is an image with flat areas (run mode, long runs and run interruptions), smooth
ramps, edges, noise and both extremes (clamping and modulo reduction), at a bit depth,
a NEAR value, a component count and an interleave mode. CharLS (through pyjpegls, the
decoder pydicom uses) encodes it to NAME.jls and decodes that back to NAME.raw, its own
output bytes (one byte a sample up to 8 bits, two little-endian bytes above; planar for
interleave mode 0, pixel-interleaved otherwise). glint's decoder must give NAME.raw from
NAME.jls, byte for byte. The output is deterministic (a seeded generator).

Usage (in a venv, any Python >= 3.9):
    python3 -m venv /tmp/jls && /tmp/jls/bin/pip install pyjpegls==1.5.1 numpy
    /tmp/jls/bin/python scripts/jpegls-fixtures.py [OUTDIR]
"""
import os
import sys

import jpeg_ls
import numpy as np

# name: (bits, near, components, interleave mode, rows, columns)
CASES = {
    "grey8-lossless": (8, 0, 1, 0, 23, 37),
    "grey8-near3": (8, 3, 1, 0, 23, 37),
    "grey2-lossless": (2, 0, 1, 0, 23, 37),
    "grey5-near1": (5, 1, 1, 0, 23, 37),
    "grey10-lossless": (10, 0, 1, 0, 23, 37),
    "grey12-lossless": (12, 0, 1, 0, 23, 37),
    "grey12-near2": (12, 2, 1, 0, 23, 37),
    "grey16-lossless": (16, 0, 1, 0, 23, 37),
    "grey16-near5": (16, 5, 1, 0, 23, 37),
    "grey8-long-runs": (8, 0, 1, 0, 3, 1500),
    "rgb8-ilv0": (8, 0, 3, 0, 19, 29),
    "rgb8-ilv1": (8, 0, 3, 1, 19, 29),
    "rgb8-ilv2": (8, 0, 3, 2, 19, 29),
    "rgb8-ilv1-near2": (8, 2, 3, 1, 19, 29),
    "rgb8-ilv2-near2": (8, 2, 3, 2, 19, 29),
    "rgb12-ilv2": (12, 0, 3, 2, 19, 29),
    "rgb16-ilv1": (16, 0, 3, 1, 19, 29),
}


def image(rng, bits, comps, rows, cols):
    """Planes (comps, rows, cols) of mixed content in 0 .. 2^bits - 1."""
    top = (1 << bits) - 1
    y, x = np.mgrid[0:rows, 0:cols]
    planes = []
    for c in range(comps):
        ramp = (x * (c + 1) * top) // max(cols - 1, 1)
        img = np.where(y % 7 < 3, top // 3, ramp)  # flat bands: run mode
        img = np.where((x // 5 + y // 4 + c) % 6 == 0, top, img)  # edges and the maximum
        img = np.where((x + 2 * y) % 11 == 0, 0, img)  # the minimum
        noisy = (y % 7 == 5) | (x > cols * 3 // 4)
        img = np.where(noisy, rng.integers(0, top + 1, size=img.shape), img)
        if cols > 1000:  # long runs broken by a few interruptions
            img = np.full((rows, cols), top // 2)
            img[:, rng.integers(0, cols, size=6)] = top
        planes.append(np.clip(img, 0, top))
    return np.stack(planes)


def layout(planes, ilv):
    """The sample order CharLS takes for an interleave mode."""
    if ilv == 0:
        return planes  # (c, r, w)
    if ilv == 1:
        return planes.transpose(1, 0, 2)  # (r, c, w)
    return planes.transpose(1, 2, 0)  # (r, w, c)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        root, "crates/io/tests/data/jpegls")
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(39)
    for name, (bits, near, comps, ilv, rows, cols) in CASES.items():
        planes = image(rng, bits, comps, rows, cols)
        dtype = "<u1" if bits <= 8 else "<u2"
        src = np.ascontiguousarray(layout(planes, ilv)).astype(dtype).tobytes()
        jls = jpeg_ls.encode_buffer(src, rows, cols, comps, bits, lossy_error=near,
                                    interleave_mode=ilv if comps > 1 else None)
        raw, info = jpeg_ls.decode_buffer(bytes(jls))
        assert info["bits_per_sample"] == bits and info["components"] == comps, info
        if near == 0:
            assert bytes(raw) == src, f"{name}: CharLS's lossless round trip differs"
        with open(os.path.join(out, name + ".jls"), "wb") as f:
            f.write(jls)
        with open(os.path.join(out, name + ".raw"), "wb") as f:
            f.write(raw)
        print(f"{name}: {len(jls)} bytes, {len(raw)} decoded")


if __name__ == "__main__":
    main()
