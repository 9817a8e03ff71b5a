#!/usr/bin/env python3
"""A thumbnail PNG per volume of a directory of scans, rendered by a process pool.

    python examples/python/thumbnails.py SCANS_DIR OUT_DIR [--size 256] [--workers N]
        [--preset mr-t2-brain] [--view anterior] [--lobe k]

Finds NIfTI (.nii, .nii.gz) and NRRD (.nrrd, .nhdr) files and DICOM series
(directories holding .dcm files) under SCANS_DIR and writes OUT_DIR/<name>.png for
each. Workers receive only a path and a glint.Scene (both pickle small); each reads its
volume and renders it with the GIL released. Workers are spawned, not forked: glint's
render threads (rayon) do not survive fork(). A scan that fails is reported on one line
and the others go on; the exit status is 1 if any failed.

The same `thumbnail` function runs under Dask or Ray (see docs/python.md).
"""

import argparse
import concurrent.futures as cf
import multiprocessing
import os
import pathlib
import sys

import glint

VOLUME_SUFFIXES = (".nii", ".nii.gz", ".nrrd", ".nhdr")


def find_scans(root: pathlib.Path):
    """Volume files and DICOM series directories under root, sorted."""
    scans = []
    for dirpath, _, files in os.walk(root):
        if any(f.lower().endswith(".dcm") for f in files):
            scans.append(pathlib.Path(dirpath))
        scans += [pathlib.Path(dirpath, f) for f in files if f.lower().endswith(VOLUME_SUFFIXES)]
    return sorted(scans)


def out_name(scan: pathlib.Path, root: pathlib.Path) -> str:
    """A flat file name for a scan's thumbnail: its path below root, '/' as '__'."""
    rel = scan.relative_to(root) if scan != root else pathlib.Path(scan.name)
    name = "__".join(rel.parts)
    for suffix in VOLUME_SUFFIXES:
        if name.lower().endswith(suffix):
            name = name[: -len(suffix)]
            break
    return name + ".png"


def thumbnail(scan: str, scene: glint.Scene, out: str) -> str:
    """Renders one scan to out (written atomically); returns out."""
    glint.Renderer(scan).render(scene).save(out)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scans", type=pathlib.Path)
    ap.add_argument("out", type=pathlib.Path)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--workers", type=int, default=os.cpu_count())
    ap.add_argument("--preset", help="transfer-function preset (default: guessed per scan)")
    ap.add_argument("--view", default="anterior")
    ap.add_argument("--lobe", default="k", choices=glint.lobe_kinds())
    args = ap.parse_args(argv)

    scans = find_scans(args.scans)
    if not scans:
        print(f"thumbnails: no volumes under {args.scans}", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    scene = glint.Scene(
        size=(args.size, args.size),
        preset=args.preset,
        camera={"view": args.view},
        lobe={"kind": args.lobe},
    )
    failed = 0
    # "spawn": fresh worker processes. A forked child of a process that has rendered
    # would inherit glint's thread pool without its threads and wait forever.
    spawn = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(max_workers=args.workers, mp_context=spawn) as pool:
        jobs = {
            pool.submit(thumbnail, str(s), scene, str(args.out / out_name(s, args.scans))): s
            for s in scans
        }
        for job in cf.as_completed(jobs):
            try:
                print(job.result())
            except (OSError, ValueError) as e:
                failed += 1
                print(f"thumbnails: {jobs[job]}: {e}", file=sys.stderr)
    print(f"thumbnails: {len(scans) - failed} of {len(scans)} rendered", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
