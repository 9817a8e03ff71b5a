#!/usr/bin/env python3
"""The converged comparison of glint's pure-medium path tracing with Mitsuba 3's
`volpath` (issue 41 item 4): every case of medium.cases rendered by both in K
independent batches, and a Markdown table of the agreement (docs/lighting.md).

Needs the glint Python package and mitsuba in one interpreter: the venv of
scripts/test-python holds both (crates/python/tests/requirements.txt pins mitsuba):

    $CARGO_TARGET_DIR/py-venv/bin/python scripts/mitsuba/compare-mitsuba.py --size 64 --spp 256

Writes each case's mean
images as float32 .npy and the Mitsuba grids (.vol) under --out.
"""

import argparse
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import medium as gm  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=64, help="image width and height, pixels")
    p.add_argument("--grid", type=int, default=32, help="voxels per side of the media")
    p.add_argument("--spp", type=int, default=256, help="samples per pixel of a batch")
    p.add_argument("--batches", type=int, default=8, help="independent batches per renderer")
    p.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("mitsuba-compare"))
    args = p.parse_args()
    if args.size < 2 or args.grid < 12 or args.spp < 1 or args.batches < 2:
        print("compare: expected --size >= 2, --grid >= 12, --spp >= 1, --batches >= 2", file=sys.stderr)
        return 2
    import glint
    import mitsuba as mi

    mi.set_variant(args.variant)
    size, k = (args.size, args.size), args.batches
    print(
        f"{args.size}x{args.size} pixels, {args.grid}^3 voxels, {k} batches of {args.spp} spp each "
        f"(glint seeds 1..{k}, Mitsuba {args.variant} seeds {k + 1}..{2 * k})\n"
    )
    print("| case | glint s | Mitsuba s | mean rel. diff | total rel. diff | total z | mean z^2 | share abs(z) > 4 |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    args.out.mkdir(parents=True, exist_ok=True)
    for name, case in gm.cases(args.grid).items():
        t = time.perf_counter()
        g = gm.batches(lambda s: gm.render_glint(glint, case, size, args.spp, s)[0], k)
        tg = time.perf_counter() - t
        derived = gm.render_glint(glint, case, size, 1, 0)[1]
        scene = gm.MitsubaCase(mi, case, derived, size, args.out)
        t = time.perf_counter()
        m = gm.batches(lambda s: scene.render(args.spp, s), k, first_seed=k + 1)
        tm = time.perf_counter() - t
        a = gm.agreement(g, m)
        np.save(args.out / f"{name}-glint.npy", g.mean(0).astype(np.float32))
        np.save(args.out / f"{name}-mitsuba.npy", m.mean(0).astype(np.float32))
        print(
            f"| {name} | {tg:.1f} | {tm:.1f} | {a.mean_rel_diff:.4f} | {a.total_rel_diff:+.5f} | "
            f"{a.total_z:+.2f} | {a.mean_z2:.3f} | {a.share_over_4:.4f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
