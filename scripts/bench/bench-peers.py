#!/usr/bin/env python3
"""Equal-time error of glint, Mitsuba 3 and Blender Cycles on the same medium (issue 41
item 6): the heterogeneous blob of scripts/mitsuba/medium.py (extinction per mm
`sigma * v`, constant albedo, Henyey-Greenstein g, a uniform environment and a
directional light), classified by glint and exported as a grid (Mitsuba's .vol, an .npy
for Cycles), rendered by each at about 1 s and 10 s of wall time, each image's error
to a converged reference of the same renderer (its noise; the references' differences
are printed apart, as bias).

    scripts/bench/bench-peers --size 128    (the command beside it: venvs, release build)

glint: the release command with `--time-budget MS` (adaptive passes), wall time of the
process (reading the volume and classifying included). Mitsuba: `llvm_ad_rgb` if it
loads (Debian's libllvm19), else `scalar_rgb` (said in the output); the sample count for
a target time from a timed 16-spp render after a warm-up (the JIT's kernels cached),
wall time of `mi.render`. Cycles (the `bpy` wheel, its own venv): `time_limit` at the
target, OIDN off and on, wall time of the render call (scene sync and the geometry
nodes that build its grid included, OIDN included). Error: relative MSE, the mean over
pixels and channels of (x - ref)^2 / (ref^2 + 0.01).
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "mitsuba"))
import medium as gm  # noqa: E402


def rel_mse(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.mean((x - ref) ** 2 / (ref**2 + 0.01)))


def read_pfm(path: pathlib.Path) -> np.ndarray:
    """A colour Portable Float Map (glint's -o x.pfm), rows top to bottom."""
    data = path.read_bytes()
    parts = data.split(b"\n", 3)
    assert parts[0] == b"PF", "not a colour PFM"
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    a = np.frombuffer(parts[3], dtype="<f4" if scale < 0 else ">f4", count=w * h * 3)
    return a.reshape(h, w, 3)[::-1].astype(np.float64)


class Glint:
    def __init__(self, glint, case, size, work):
        import nibabel

        self.bin = os.environ.get("GLINT_BIN", str(ROOT / "target" / "release" / "glint"))
        nii = work / "blob.nii"
        nibabel.save(nibabel.Nifti1Image(case.values, np.diag([case.spacing] * 3 + [1.0])), str(nii))
        fields = gm.glint_fields(case, size, 1, 0)
        self.scene = work / "blob-scene.json"
        glint.Scene(**fields, input=str(nii)).save(self.scene)
        self.work = work

    def render(self, spp, seed=1, budget_ms=None):
        out = self.work / "glint.pfm"
        cmd = [self.bin, "render", "--scene", str(self.scene), "--spp", str(spp), "--seed", str(seed), "-o", str(out)]
        if budget_ms:
            cmd += ["--time-budget", str(budget_ms)]
        t = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        return read_pfm(out), time.perf_counter() - t


class Mitsuba:
    def __init__(self, case, derived, size, work):
        import mitsuba as mi

        self.variant = "llvm_ad_rgb"
        try:
            mi.set_variant("llvm_ad_rgb")
            mi.Float(1.0) + 1.0  # forces the LLVM backend to load
        except Exception as e:  # noqa: BLE001: any failure to load means no LLVM
            print(f"Mitsuba llvm_ad_rgb unavailable ({e}); scalar_rgb", file=sys.stderr)
            mi.set_variant("scalar_rgb")
            self.variant = "scalar_rgb"
        self.case = gm.MitsubaCase(mi, case, derived, size, work)

    def render(self, spp, seed=1):
        t = time.perf_counter()
        img = self.case.render(spp, seed)
        return img, time.perf_counter() - t


class Cycles:
    def __init__(self, case, derived, size, work):
        self.python = os.environ.get("BPY_PYTHON", "/work/venv-bpy/bin/python")
        np.save(work / "density.npy", (case.values * case.sigma).astype(np.float32))
        lo, ext = gm.grid_box(case.values.shape, case.spacing)
        light = None
        if case.light is not None:
            az, el, intensity = case.light
            towards = gm.light_direction(derived, az, el)
            light = {"towards": towards.tolist(), "irradiance": float(np.pi * intensity)}
        self.spec = {
            "density": str(work / "density.npy"),
            "lo_mm": lo.tolist(),
            "size_mm": ext.tolist(),
            "albedo": list(case.albedo),
            "g": case.g,
            "environment": case.environment,
            "light": light,
            "camera": {k: derived[k] for k in ("eye", "focal_point", "view_up", "view_angle_deg")},
            "size": list(size),
            "bounces": case.bounces,
        }
        self.work = work

    def render(self, samples, time_limit=0.0, denoise=False, seed=1):
        spec = dict(self.spec, samples=samples, time_limit=time_limit, denoise=denoise, seed=seed)
        spec["out"] = str(self.work / "cycles.npy")
        path = self.work / "cycles-spec.json"
        path.write_text(json.dumps(spec))
        p = subprocess.run(
            [self.python, str(ROOT / "scripts" / "bench" / "bench-peers-cycles.py"), str(path)],
            check=True,
            capture_output=True,
            text=True,
        )
        seconds = json.loads(p.stdout.strip().splitlines()[-1])["seconds"]
        return np.load(spec["out"]).astype(np.float64), seconds


def equal_time(renderer, label, targets, ref):
    """Rows of `renderer` at uniform sampling: for each target time, the sample count
    that fills it (scaled from a 16-spp render's time), its time and error to `ref`."""
    _, t16 = renderer.render(16)
    rows = []
    for target in targets:
        spp = max(1, int(round(16 * target / t16)))
        img, t = renderer.render(spp)
        rows.append((f"{label} ({spp} spp)", target, t, rel_mse(img, ref)))
    return rows


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--grid", type=int, default=64)
    p.add_argument("--ref-spp", type=int, default=4096)
    p.add_argument("--times", default="1,10", help="target seconds, comma-separated")
    p.add_argument("--skip", default="", help="renderers to leave out: glint,mitsuba,cycles")
    args = p.parse_args()
    import glint

    case = gm.cases(args.grid)["blob-light"]
    size = (args.size, args.size)
    skip = set(filter(None, args.skip.split(",")))
    targets = [float(t) for t in args.times.split(",")]
    work = pathlib.Path(tempfile.mkdtemp(prefix="bench-peers-"))
    derived = gm.render_glint(glint, case, size, 1, 0)[1]
    rows, refs = [], {}
    print(f"blob {args.grid}^3, {args.size}x{args.size}, references {args.ref_spp} spp; machine load {os.getloadavg()[0]:.1f}", flush=True)

    if "glint" not in skip:
        g = Glint(glint, case, size, work)
        ref, t = g.render(args.ref_spp, seed=1000)
        refs["glint"] = ref
        print(f"glint reference: {t:.1f} s", flush=True)
        for target in targets:
            img, t = g.render(65536, budget_ms=int(target * 1000))
            rows.append(("glint (time budget)", target, t, rel_mse(img, ref)))
        # Uniform sampling at the count that fills the target (the budget's adaptive
        # passes stop by themselves once no pixel's relative error is over 0.02).
        rows += equal_time(g, "glint", targets, ref)
    if "mitsuba" not in skip:
        m = Mitsuba(case, derived, size, work)
        m.render(4)  # warm-up: compile the kernels
        ref, t = m.render(args.ref_spp, seed=1000)
        refs["mitsuba"] = ref
        print(f"Mitsuba {m.variant} reference: {t:.1f} s", flush=True)
        rows += equal_time(m, f"Mitsuba 3 {m.variant}", targets, ref)
    if "cycles" not in skip:
        c = Cycles(case, derived, size, work)
        ref, t = c.render(args.ref_spp, seed=1000)
        refs["cycles"] = ref
        print(f"Cycles reference: {t:.1f} s", flush=True)
        for target in targets:
            for denoise in (False, True):
                img, t = c.render(1 << 20, time_limit=target, denoise=denoise)
                name = "Cycles, OIDN on" if denoise else "Cycles, OIDN off"
                rows.append((name, target, t, rel_mse(img, ref)))

    print("\n| renderer | target s | wall s | relative MSE to its reference |")
    print("| --- | --- | --- | --- |")
    for name, target, t, err in rows:
        print(f"| {name} | {target:g} | {t:.2f} | {err:.2e} |")
    if "glint" in refs:
        for other in ("mitsuba", "cycles"):
            if other in refs:
                r, o = refs["glint"], refs[other]
                print(f"\nreference bias: {other} vs glint: mean relative difference "
                      f"{np.abs(o - r).sum() / r.sum():.4f}, totals {o.sum() / r.sum() - 1:+.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
