"""glint's `path` lighting as a pure medium, checked against Mitsuba 3's `volpath`
(issue 41 item 4), and the exporter of a classified volume the benchmark of item 6 uses.

Units (docs/lighting.md, "Units"): lengths in mm (glint's world space, RAS+); extinction
per mm; the environment a radiance; a glint light of intensity `I` the irradiance `pi*I`
(Mitsuba's `directional` emitter takes the irradiance). A case's medium is
`sigma_t(x) = sigma * v(x)` with `v` the trilinearly interpolated voxel values and a
constant single-scattering albedo and Henyey-Greenstein `g`, so glint and Mitsuba see
the same field:

- glint: the values as a volume, a transfer function whose opacity per `opacity_unit` mm
  is `1 - exp(-sigma * v * unit)` (so glint's extinction `-ln(1 - alpha) / unit` is
  `sigma * v`, tabulated at 257 points and 4096 bins: error below 1e-4 of sigma), colour
  the albedo (sRGB-encoded; the material's diffuse 1, so glint's albedo
  `srgb_to_linear(colour) * diffuse` is the albedo), `lighting.surface_weight` 0 (a pure
  medium), `prefilter` none (the voxels as stored);
- Mitsuba: the same values as a `.vol` grid (`gridvolume`, trilinear, cell-centred:
  voxel `i` at `i * spacing` mm as in glint, the grid's box from `-spacing/2` to
  `(n - 1/2) * spacing`), `heterogeneous` medium of `scale = sigma`, inside a `cube`
  with a `null` BSDF.

The volumes have zero borders (at least two voxels), so where each renderer ends its
grid does not matter. glint's camera is read back from the resolved scene's `derived`
(eye, focal point, up, vertical view angle) and given to Mitsuba's `perspective`
sensor; both use a one-pixel box filter. glint's `bounces` (scattering events) is
Mitsuba's `max_depth - 1`.

The `.vol` files are written by Mitsuba's own `mitsuba.VolumeGrid.write` (the format's
reference implementation), not by hand.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
from typing import Callable, Dict, Optional, Sequence, Tuple

import numpy as np

#: Transfer-function points of a case's extinction ramp.
TF_POINTS = 257


def linear_to_srgb(x: float) -> float:
    """The sRGB encoding of a linear component (glint's transfer-function colours are
    sRGB; it decodes them with the inverse)."""
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """The sRGB decoding glint applies to transfer-function colours."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


@dataclasses.dataclass(frozen=True)
class Case:
    """A medium and its lighting, in glint's and Mitsuba's common units."""

    name: str
    #: Voxel values in [0, 1], indexed [i, j, k] (i along x), zero borders.
    values: np.ndarray
    #: Voxel spacing, mm (isotropic).
    spacing: float
    #: Extinction per mm at value 1.
    sigma: float
    #: Single-scattering albedo, linear RGB.
    albedo: Tuple[float, float, float]
    #: Henyey-Greenstein anisotropy.
    g: float
    #: Radiance of the uniform white environment.
    environment: float
    #: A directional light (azimuth deg, elevation deg, intensity I), relative to the
    #: camera as glint's lights are; irradiance pi*I.
    light: Optional[Tuple[float, float, float]] = None
    #: Most scattering events (glint's bounces).
    bounces: int = 4


def sphere(n: int) -> np.ndarray:
    """A homogeneous ball of value 1 on an n^3 grid (radius n/2 - 3 voxels)."""
    c = (n - 1) / 2
    i, j, k = np.meshgrid(*(np.arange(n),) * 3, indexing="ij")
    r = np.sqrt((i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2)
    return (r <= n / 2 - 3).astype(np.float32)


def blob(n: int) -> np.ndarray:
    """A heterogeneous, asymmetric blob: three Gaussians, peak 1, zero borders."""
    x = np.linspace(-1, 1, n)
    i, j, k = np.meshgrid(x, x, x, indexing="ij")
    v = (
        np.exp(-((i + 0.2) ** 2 + j**2 + (k - 0.1) ** 2) / 0.12)
        + 0.7 * np.exp(-((i - 0.35) ** 2 + (j - 0.25) ** 2 + (k + 0.3) ** 2) / 0.05)
        + 0.5 * np.exp(-((i - 0.1) ** 2 + (j + 0.4) ** 2 + (k - 0.4) ** 2) / 0.03)
    )
    v = v / v.max()
    v[v < 0.02] = 0.0
    v[:2], v[-2:], v[:, :2], v[:, -2:], v[:, :, :2], v[:, :, -2:] = 0, 0, 0, 0, 0, 0
    return v.astype(np.float32)


def cases(n: int) -> Dict[str, Case]:
    """The comparison's cases on n^3 grids of 1 mm voxels: a homogeneous ball lit by the
    environment alone at g = 0 and g = 0.6, and a heterogeneous blob of a coloured
    albedo lit by the environment and a directional light."""
    ball = sphere(n)
    s = 2.5 / (n / 2 - 3)  # optical radius 2.5
    return {
        "ball-g0": Case("ball-g0", ball, 1.0, s, (0.9, 0.9, 0.9), 0.0, 1.0),
        "ball-g0.6": Case("ball-g0.6", ball, 1.0, s, (0.9, 0.9, 0.9), 0.6, 1.0),
        "blob-light": Case(
            "blob-light", blob(n), 1.0, 2 * s, (0.9, 0.7, 0.5), -0.3, 0.2, (40.0, 30.0, 1.0)
        ),
    }


def transfer_function(case: Case) -> dict:
    """glint's transfer function of the case: extinction `sigma * v` per mm (opacity
    per `case.spacing` mm), colour the albedo."""
    unit = case.spacing
    v = np.linspace(0.0, 1.0, TF_POINTS)
    alpha = 1.0 - np.exp(-case.sigma * v * unit)
    rgb = [linear_to_srgb(a) for a in case.albedo]
    return {
        "opacity": [[float(x), float(a)] for x, a in zip(v, alpha)],
        "color": [[0.0, *rgb], [1.0, *rgb]],
    }


def glint_fields(case: Case, size: Tuple[int, int], spp: int, seed: int) -> dict:
    """The fields of glint's scene (glint.Scene(**fields); the same keys as the
    JSON of `glint render --scene`)."""
    lights = []
    if case.light is not None:
        az, el, intensity = case.light
        lights = [{"azimuth": az, "elevation": el, "intensity": intensity}]
    return {
        "size": list(size),
        "prefilter": "none",
        "transfer_function": transfer_function(case),
        "opacity_unit": case.spacing,
        "material": {"ambient": 0.0, "diffuse": 1.0, "specular": 0.0},
        "lights": lights,
        "lighting": {
            "model": "path",
            "spp": spp,
            "seed": seed,
            "bounces": case.bounces,
            "environment": case.environment,
            "anisotropy": case.g,
            "show_environment": True,
            "surface_weight": 0.0,
        },
    }


def render_glint(glint, case: Case, size: Tuple[int, int], spp: int, seed: int):
    """glint's linear radiance (H, W, 3) and the resolved scene's `derived` camera."""
    volume = glint.Volume.from_array(case.values, spacing=(case.spacing,) * 3)
    image = glint.Renderer(volume).render(glint.Scene(**glint_fields(case, size, spp, seed)))
    return np.asarray(image.linear, dtype=np.float64), image.scene.to_dict()["derived"]


def light_direction(derived: dict, azimuth: float, elevation: float) -> np.ndarray:
    """The world direction towards a glint light (glint_core's `Light::direction`)."""
    eye, focal = np.array(derived["eye"]), np.array(derived["focal_point"])
    forward = (focal - eye) / np.linalg.norm(focal - eye)
    up = np.array(derived["view_up"], dtype=np.float64)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    a, e = math.radians(azimuth), math.radians(elevation)
    d = (-forward * math.cos(a) + right * math.sin(a)) * math.cos(e) + up * math.sin(e)
    return d / np.linalg.norm(d)


def write_vol(mi, path: pathlib.Path, grid: np.ndarray) -> None:
    """Writes an [i, j, k] or [i, j, k, c] array as Mitsuba's binary `.vol` grid (x =
    i fastest), through Mitsuba's own `VolumeGrid.write`."""
    a = grid if grid.ndim == 4 else grid[..., None]
    zyx = np.ascontiguousarray(np.transpose(a, (2, 1, 0, 3)), dtype=np.float32)
    mi.VolumeGrid(zyx).write(str(path))


def grid_box(shape: Sequence[int], spacing: float) -> Tuple[np.ndarray, np.ndarray]:
    """The grid's box in mm, cell-centred (voxel i at i * spacing): low corner, size."""
    lo = np.full(3, -0.5 * spacing)
    return lo, np.array(shape[:3], dtype=np.float64) * spacing


def mitsuba_scene(
    mi,
    case: Case,
    derived: dict,
    size: Tuple[int, int],
    sigma_path: pathlib.Path,
    albedo_path: Optional[pathlib.Path] = None,
) -> dict:
    """Mitsuba's scene dict of the case (write its grid with `write_vol` first). With
    `albedo_path` the albedo is that RGB grid, else the case's constant albedo."""
    T = mi.ScalarTransform4f
    lo, extent = grid_box(case.values.shape, case.spacing)
    grid_to_world = T().translate(lo.tolist()).scale(extent.tolist())
    cube_to_world = T().translate((lo + extent / 2).tolist()).scale((extent / 2).tolist())
    albedo = (
        {"type": "gridvolume", "filename": str(albedo_path), "to_world": grid_to_world}
        if albedo_path is not None
        else {"type": "rgb", "value": list(case.albedo)}
    )
    medium = {
        "type": "heterogeneous",
        "sigma_t": {
            "type": "gridvolume",
            "filename": str(sigma_path),
            "to_world": grid_to_world,
            "filter_type": "trilinear",
        },
        "albedo": albedo,
        "scale": case.sigma,
        "phase": {"type": "hg", "g": case.g},
    }
    w, h = size
    scene = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": case.bounces + 1},
        "sensor": {
            "type": "perspective",
            "fov": derived["view_angle_deg"],
            "fov_axis": "y",
            "near_clip": 0.01,
            "far_clip": 1e5,
            "to_world": T().look_at(
                origin=derived["eye"], target=derived["focal_point"], up=derived["view_up"]
            ),
            "sampler": {"type": "independent"},
            "film": {
                "type": "hdrfilm",
                "width": w,
                "height": h,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
        "environment": {
            "type": "constant",
            "radiance": {"type": "rgb", "value": case.environment},
        },
        "medium_box": {
            "type": "cube",
            "to_world": cube_to_world,
            "bsdf": {"type": "null"},
            "interior": medium,
        },
    }
    if case.light is not None:
        az, el, intensity = case.light
        towards = light_direction(derived, az, el)
        scene["light"] = {
            "type": "directional",
            "direction": (-towards).tolist(),
            "irradiance": {"type": "rgb", "value": math.pi * intensity},
        }
    return scene


class MitsubaCase:
    """A case loaded into Mitsuba once (its grid written to `folder`), rendered at any
    sample count and seed."""

    def __init__(self, mi, case: Case, derived: dict, size: Tuple[int, int], folder: pathlib.Path):
        folder.mkdir(parents=True, exist_ok=True)
        sigma_path = folder / f"{case.name}-density.vol"
        write_vol(mi, sigma_path, case.values)
        self.mi = mi
        self.scene = mi.load_dict(mitsuba_scene(mi, case, derived, size, sigma_path))

    def render(self, spp: int, seed: int) -> np.ndarray:
        """Linear radiance (H, W, 3)."""
        return np.array(self.mi.render(self.scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]


#: Relative rounding of a noiseless pixel: a renderer's float sums round (Mitsuba's
#: film gives 0.19999987 for an environment of 0.2 seen through empty space, glint 0.2
#: exactly), which alone is no disagreement.
ROUNDING = 1e-5


@dataclasses.dataclass
class Agreement:
    """Two renderers' images of one case compared within their noise, from k
    independent batches (seeds) of each."""

    #: Mean relative difference: sum |mean_a - mean_b| over sum mean_b (all pixels
    #: and channels; noise included).
    mean_rel_diff: float
    #: Signed relative difference of the images' totals (sums over pixels and
    #: channels), and its z-score against the totals' standard errors (from the
    #: batches).
    total_rel_diff: float
    total_z: float
    #: Per pixel and channel with noise (the standard error sqrt(se_a^2 + se_b^2) from
    #: the batches' spread over 10 times the rounding `ROUNDING`): z = (mean_a -
    #: mean_b) / sqrt(se_a^2 + se_b^2 + rounding^2), the mean of z^2 (1 for normal
    #: errors; more with few batches, as Student's t has) and the share with |z| > 4.
    mean_z2: float
    share_over_4: float
    #: Pixels and channels without noise above rounding in both (e.g. the environment
    #: seen through empty space), and how many of them differ by more than 4 times
    #: their rounding and standard error.
    quiet: int
    quiet_differ: int

    def passes(self, max_mean_z2: float, max_total_z: float = 4.0) -> bool:
        """The CI check's test: mean z^2 at most `max_mean_z2`, the totals within
        `max_total_z` standard errors, and the noiseless pixels equal up to rounding."""
        return (
            self.mean_z2 <= max_mean_z2
            and abs(self.total_z) <= max_total_z
            and self.quiet_differ == 0
        )


def agreement(a: np.ndarray, b: np.ndarray) -> Agreement:
    """Compares batches `a` and `b`, each (k, H, W, 3) of independent batch means."""
    ka, kb = len(a), len(b)
    ma, mb = a.mean(0), b.mean(0)
    se2 = a.var(0, ddof=1) / ka + b.var(0, ddof=1) / kb
    floor = ROUNDING * np.maximum(np.abs(ma), np.abs(mb))
    noisy = se2 > (10 * floor) ** 2
    z = (ma - mb)[noisy] / np.sqrt(se2[noisy] + floor[noisy] ** 2)
    quiet = ~noisy
    limit = 4 * (floor[quiet] + np.sqrt(se2[quiet]))
    quiet_differ = int(np.count_nonzero(np.abs(ma - mb)[quiet] > limit))
    ta, tb = a.sum(axis=(1, 2, 3)), b.sum(axis=(1, 2, 3))
    dt = ta.mean() - tb.mean()
    tz = dt / math.sqrt(ta.var(ddof=1) / ka + tb.var(ddof=1) / kb)
    return Agreement(
        mean_rel_diff=float(np.abs(ma - mb).sum() / mb.sum()),
        total_rel_diff=float(dt / tb.mean()),
        total_z=float(tz),
        mean_z2=float(np.mean(z**2)) if z.size else 0.0,
        share_over_4=float(np.mean(np.abs(z) > 4)) if z.size else 0.0,
        quiet=int(np.count_nonzero(quiet)),
        quiet_differ=quiet_differ,
    )


def batches(render: Callable[[int], np.ndarray], k: int, first_seed: int = 1) -> np.ndarray:
    """k images of `render(seed)`, seeds first_seed.., stacked (k, H, W, 3)."""
    return np.stack([render(first_seed + s) for s in range(k)])


def compare_case(glint, mi, case: Case, size: Tuple[int, int], spp: int, k: int, folder: pathlib.Path):
    """Renders k batches of `spp` samples of `case` in glint and Mitsuba (seeds 1..k)
    and compares them: the Agreement and both means."""
    g = batches(lambda s: render_glint(glint, case, size, spp, s)[0], k)
    derived = render_glint(glint, case, size, 1, 0)[1]
    m_case = MitsubaCase(mi, case, derived, size, folder)
    m = batches(lambda s: m_case.render(spp, s), k)
    return agreement(g, m), g.mean(0), m.mean(0)


def classify(values: np.ndarray, tf: dict, unit_mm: float, diffuse: float) -> Tuple[np.ndarray, np.ndarray]:
    """A volume classified as glint classifies it for `path` lighting
    (glint-volume's `Medium`): per voxel the extinction per mm `-ln(1 - alpha(v)) /
    unit_mm` (alpha the transfer function's piecewise-linear opacity, at most
    1 - 1e-6) and the albedo `srgb_to_linear(colour(v)) * diffuse`. glint interpolates
    the values and then classifies (on 4096 bins); a renderer reading these grids
    interpolates the classified values, which differs where the transfer function
    bends between two voxels' values."""
    v = np.asarray(values, dtype=np.float64)
    op = np.array(tf["opacity"], dtype=np.float64)
    col = np.array(tf["color"], dtype=np.float64)
    alpha = np.clip(np.interp(v, op[:, 0], op[:, 1]), 0.0, 1.0 - 1e-6)
    sigma = -np.log1p(-alpha) / unit_mm
    albedo = np.stack([srgb_to_linear(np.interp(v, col[:, 0], col[:, c])) for c in (1, 2, 3)], axis=-1)
    return sigma.astype(np.float32), (albedo * diffuse).astype(np.float32)


def export_medium(glint, mi, volume, fields: dict, folder: pathlib.Path) -> dict:
    """Writes the medium glint's `path` lighting sees in `volume` under the scene
    `fields` as Mitsuba grids: `density.vol` (extinction per mm) and `albedo.vol`
    (linear RGB), cell-centred on the volume's voxels. Returns the grids' box in mm
    and the scene's `derived` camera. The volume's affine must be diagonal (axis-aligned
    voxels); glint's binomial prefilter is left to the scene (use `prefilter` none for
    the voxels as stored)."""
    affine = np.asarray(volume.affine)
    if np.count_nonzero(affine[:3, :3] - np.diag(np.diag(affine[:3, :3]))) or np.any(np.diag(affine)[:3] <= 0):
        raise ValueError("export_medium: the volume's affine is not diagonal with positive spacing")
    image = glint.Renderer(volume).render(glint.Scene(**{**fields, "size": [8, 8]}))
    scene = image.scene.to_dict()
    derived = scene["derived"]
    unit = scene.get("opacity_unit") or derived["min_spacing_mm"]
    diffuse = scene["material"].get("diffuse", 0.9) if isinstance(scene.get("material"), dict) else 0.9
    sigma, albedo = classify(volume.fdata(), derived["transfer_function"], unit, diffuse)
    folder.mkdir(parents=True, exist_ok=True)
    write_vol(mi, folder / "density.vol", sigma)
    write_vol(mi, folder / "albedo.vol", albedo)
    spacing = np.diag(affine)[:3]
    lo = affine[:3, 3] - 0.5 * spacing
    return {
        "lo_mm": lo.tolist(),
        "size_mm": (np.array(sigma.shape) * spacing).tolist(),
        "derived": derived,
        "sigma": sigma,
        "albedo": albedo,
    }
