//! The pictures of an input: its views side by side, and three orthogonal slices.

use glint_io::affine::{inverse3, linear_part, mul3};
use glint_io::Volume;
use glint_render::{srgb_to_linear, Image, RenderStats};

use crate::BatchError;

/// The linear float mosaic's file name, written beside `mosaic.png` when the spec
/// asks for it ([`Spec::exr`](crate::Spec::exr)).
pub const MOSAIC_EXR_FILE: &str = "mosaic.exr";

/// The mosaic's linear radiance as OpenEXR bytes: R, G, B and A as 32-bit floats,
/// the pixels as rendered before any tone curve, sRGB encoding or clip (the render
/// crate's writer, [`Image::encode_exr`], the one `glint render -o x.exr` uses).
pub fn mosaic_exr(picture: &Image) -> Result<Vec<u8>, BatchError> {
    picture.encode_exr().map_err(BatchError::Render)
}

/// The views side by side, left to right, on one row (every tile as tall as the
/// first).
pub fn mosaic(tiles: &[Image]) -> Result<Image, BatchError> {
    let Some(first) = tiles.first() else {
        return Err(BatchError::Spec("a mosaic of no view".into()));
    };
    let height = first.height;
    if let Some(odd) = tiles.iter().find(|t| t.height != height) {
        return Err(BatchError::Spec(format!(
            "the views differ in height ({} and {} pixels)",
            height, odd.height
        )));
    }
    let width: u32 = tiles.iter().map(|t| t.width).sum();
    let mut rgb = Vec::with_capacity(width as usize * height as usize);
    let mut alpha = Vec::with_capacity(rgb.capacity());
    for y in 0..height as usize {
        for t in tiles {
            let row = y * t.width as usize..(y + 1) * t.width as usize;
            rgb.extend_from_slice(&t.rgb[row.clone()]);
            alpha.extend_from_slice(&t.alpha[row]);
        }
    }
    Ok(Image {
        width,
        height,
        rgb,
        alpha,
        stats: RenderStats::default(),
    })
}

/// The intensity window of the slices: values at or below `lo` are black, at or above
/// `hi` white, linear in between (on the sRGB scale a PNG viewer shows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// The black level.
    pub lo: f64,
    /// The white level.
    pub hi: f64,
}

impl Window {
    /// The volume's robust range ([`Volume::robust_range`]: the 0.5th and 99.5th
    /// percentiles), the window of all three slices; `None` for a volume without
    /// finite values.
    pub fn of(volume: &Volume) -> Option<Window> {
        let (lo, hi) = volume.robust_range()?;
        Some(Window { lo, hi })
    }

    /// The grey level of a value, 0 to 1 (0 for NaN; a window of zero width splits
    /// at its value).
    pub fn grey(&self, value: f64) -> f64 {
        if value.is_nan() {
            return 0.0;
        }
        if self.hi <= self.lo {
            return if value > self.lo { 1.0 } else { 0.0 };
        }
        ((value - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0)
    }
}

/// The world axes (RAS+: 0 = x, 1 = y, 2 = z) of each slice, the image's right and up:
/// sagittal (anterior to the right), coronal and axial (the patient's right to the
/// right, the neurological convention; anterior up in the axial slice), as nilearn's
/// `plot_anat` shows them.
const PANELS: [(usize, usize); 3] = [(1, 2), (0, 2), (0, 1)];

/// Sagittal, coronal and axial slices through the centre of the volume's bounding
/// box, side by side, each `tile` pixels, in world (RAS+) orientation: each slice is
/// resampled (trilinear) along the world axes through the voxel-to-world affine,
/// scaled to fit its tile with square pixels; outside the volume is black with zero
/// opacity.
pub fn slices(volume: &Volume, tile: [u32; 2], window: Window) -> Result<Image, BatchError> {
    let [w, h] = tile;
    if w == 0 || h == 0 {
        return Err(BatchError::Spec("slices of zero size".into()));
    }
    let a = &volume.affine;
    let inverse = inverse3(&linear_part(a)).ok_or_else(|| {
        BatchError::Spec("the voxel-to-world affine is singular: no slices".into())
    })?;
    let (lo, hi) = bounds(volume);
    let centre: [f64; 3] = std::array::from_fn(|i| (lo[i] + hi[i]) / 2.0);
    let mut tiles = Vec::with_capacity(3);
    for (u, v) in PANELS {
        let extent = [hi[u] - lo[u], hi[v] - lo[v]];
        let mut mm = (extent[0] / w as f64).max(extent[1] / h as f64);
        if mm <= 0.0 || !mm.is_finite() {
            mm = 1.0;
        }
        let mut rgb = Vec::with_capacity(w as usize * h as usize);
        let mut alpha = Vec::with_capacity(rgb.capacity());
        for py in 0..h {
            for px in 0..w {
                let mut p = centre;
                p[u] += (px as f64 + 0.5 - w as f64 / 2.0) * mm;
                p[v] -= (py as f64 + 0.5 - h as f64 / 2.0) * mm;
                let q = mul3(&inverse, [p[0] - a[0][3], p[1] - a[1][3], p[2] - a[2][3]]);
                match trilinear(volume, q) {
                    Some(value) => {
                        let g = srgb_to_linear(window.grey(value)) as f32;
                        rgb.push([g; 3]);
                        alpha.push(1.0);
                    }
                    None => {
                        rgb.push([0.0; 3]);
                        alpha.push(0.0);
                    }
                }
            }
        }
        tiles.push(Image {
            width: w,
            height: h,
            rgb,
            alpha,
            stats: RenderStats::default(),
        });
    }
    mosaic(&tiles)
}

/// The world bounding box of the voxel centres.
fn bounds(volume: &Volume) -> ([f64; 3], [f64; 3]) {
    let a = &volume.affine;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for corner in 0..8 {
        let ijk: [f64; 3] =
            std::array::from_fn(|i| ((corner >> i) & 1) as f64 * (volume.dims[i] - 1) as f64);
        for r in 0..3 {
            let x = a[r][0] * ijk[0] + a[r][1] * ijk[1] + a[r][2] * ijk[2] + a[r][3];
            lo[r] = lo[r].min(x);
            hi[r] = hi[r].max(x);
        }
    }
    (lo, hi)
}

/// The volume's value at voxel coordinates `q` (trilinear; within half a voxel outside
/// the outer centres, the nearest face's value), `None` outside.
fn trilinear(volume: &Volume, q: [f64; 3]) -> Option<f64> {
    let d = volume.dims;
    let mut base = [0usize; 3];
    let mut frac = [0.0f64; 3];
    for i in 0..3 {
        let top = (d[i] - 1) as f64;
        if !(q[i] >= -0.5 && q[i] <= top + 0.5) {
            return None;
        }
        let x = q[i].clamp(0.0, top);
        let b = (x.floor() as usize).min(d[i].saturating_sub(2));
        base[i] = b;
        frac[i] = if d[i] > 1 { x - b as f64 } else { 0.0 };
    }
    let at = |di: usize, dj: usize, dk: usize| {
        let i = (base[0] + di).min(d[0] - 1);
        let j = (base[1] + dj).min(d[1] - 1);
        let k = (base[2] + dk).min(d[2] - 1);
        volume.value(i, j, k)
    };
    let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
    let c00 = lerp(at(0, 0, 0), at(1, 0, 0), frac[0]);
    let c10 = lerp(at(0, 1, 0), at(1, 1, 0), frac[0]);
    let c01 = lerp(at(0, 0, 1), at(1, 0, 1), frac[0]);
    let c11 = lerp(at(0, 1, 1), at(1, 1, 1), frac[0]);
    let c0 = lerp(c00, c10, frac[1]);
    let c1 = lerp(c01, c11, frac[1]);
    Some(lerp(c0, c1, frac[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_io::Samples;

    fn tile(width: u32, height: u32, value: f32) -> Image {
        let n = (width * height) as usize;
        Image {
            width,
            height,
            rgb: vec![[value; 3]; n],
            alpha: vec![1.0; n],
            stats: RenderStats::default(),
        }
    }

    #[test]
    fn a_mosaic_puts_the_views_side_by_side() {
        let m = mosaic(&[tile(2, 3, 0.1), tile(4, 3, 0.5)]).unwrap();
        assert_eq!((m.width, m.height), (6, 3));
        for y in 0..3 {
            assert_eq!(m.pixel(1, y), [0.1; 3]);
            assert_eq!(m.pixel(2, y), [0.5; 3]);
            assert_eq!(m.pixel(5, y), [0.5; 3]);
        }
        assert!(mosaic(&[tile(2, 3, 0.0), tile(2, 4, 0.0)]).is_err());
        assert!(mosaic(&[]).is_err());
    }

    /// A 4x6x8 volume whose value is its world x (mm, 2 mm voxels along i), then y
    /// times 100, then z times 10000: each slice's gradient shows which world axis
    /// runs along it.
    fn ramp() -> Volume {
        let dims = [4, 6, 8];
        let mut v = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    v.push((2 * i + 100 * j + 10_000 * k) as f32);
                }
            }
        }
        Volume::new(dims, [2.0, 1.0, 1.0], Samples::F32(v)).unwrap()
    }

    /// The value at a slice tile's pixel, through the window 0..1e5 (from the linear
    /// image, before the PNG's 8-bit rounding).
    fn value_at(img: &Image, panel: u32, x: u32, y: u32, tile: u32) -> f64 {
        let c = img.pixel(panel * tile + x, y)[0] as f64;
        glint_render::linear_to_srgb(c) * 1e5
    }

    #[test]
    fn slices_follow_the_world_axes() {
        let vol = ramp();
        let window = Window { lo: 0.0, hi: 1e5 };
        let n = 40;
        let img = slices(&vol, [n, n], window).unwrap();
        assert_eq!((img.width, img.height), (3 * n, n));
        // Sagittal: y (x 100) grows to the right, z (x 10000) upwards.
        let (mid, left, right) = (n / 2, n / 2 - 4, n / 2 + 4);
        let top_row = n / 2 - 12;
        let bottom_row = n / 2 + 12;
        assert!(value_at(&img, 0, right, mid, n) > value_at(&img, 0, left, mid, n));
        assert!(value_at(&img, 0, mid, top_row, n) > value_at(&img, 0, mid, bottom_row, n));
        // Axial: y grows upwards; x (x 2) to the right.
        assert!(value_at(&img, 2, mid, top_row, n) > value_at(&img, 2, mid, bottom_row, n));
        assert!(value_at(&img, 2, right, mid, n) > value_at(&img, 2, left, mid, n));
        // Outside the volume: transparent black. The sagittal slice spans z over
        // 7 mm and y over 5 mm: its left and right edges are outside.
        assert_eq!(img.alpha[(mid * 3 * n) as usize], 0.0);
        // The coronal slice at y = 2.5 mm (the centre): its pixel (mid, mid) lies half
        // a pixel right of and below the centre (x = 3 mm, z = 3.5 mm), the pixels
        // 7/40 mm (z spans 7 mm over 40 pixels).
        let mm = 7.0 / 40.0;
        let want = (3.0 + mm / 2.0) + 100.0 * 2.5 + 10_000.0 * (3.5 - mm / 2.0);
        let got = value_at(&img, 1, mid, mid, n);
        assert!((got - want).abs() < 2.0, "{got} {want}");
    }

    #[test]
    fn the_window_maps_values_to_grey() {
        let w = Window { lo: 10.0, hi: 20.0 };
        assert_eq!(w.grey(5.0), 0.0);
        assert_eq!(w.grey(15.0), 0.5);
        assert_eq!(w.grey(25.0), 1.0);
        assert_eq!(w.grey(f64::NAN), 0.0);
        let flat = Window { lo: 3.0, hi: 3.0 };
        assert_eq!((flat.grey(3.0), flat.grey(4.0)), (0.0, 1.0));
    }

    #[test]
    fn the_exr_mosaic_holds_the_linear_render_of_each_view() {
        use crate::{discover, run_job, Discover, Spec, Status};
        use glint_render::{Phantom, ReadOptions, Renderer, Scene, View};
        let data = tempfile::tempdir().unwrap();
        let path = data.path().join("vol.nii.gz");
        let vol = Phantom::SheppLogan.volume(20).unwrap();
        glint_io::nifti::write(&path, &vol, true, glint_io::Endian::Little).unwrap();
        let items = discover(std::slice::from_ref(&path), &Discover::default()).unwrap();
        let views = vec![View::Left, View::Anterior];
        let scene = Scene {
            size: [24, 20],
            ..Scene::default()
        };
        let mut spec = Spec::new(scene, views.clone(), false);
        spec.exr = true;
        let out = tempfile::tempdir().unwrap();
        let row = run_job(&items[0], &spec, out.path(), false).row;
        assert_eq!(row.status, Status::Ok, "{:?}", row.error);
        let file = out.path().join(&items[0].id).join(MOSAIC_EXR_FILE);
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &file,
            |res, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
            |(w, px), p, (r, g, b, a): (f32, f32, f32, f32)| px[p.y() * *w + p.x()] = [r, g, b, a],
        )
        .unwrap();
        let (w, px) = &read.layer_data.channel_data.pixels;
        assert_eq!((*w, read.layer_data.size.height()), (48, 20));
        // Each view rendered alone, as `glint render --view V -o x.exr` does: its
        // floats, bit for bit, in its tile.
        let mut lit = 0;
        for (k, &view) in views.iter().enumerate() {
            let scene = spec.scene_for(&path, view).unwrap();
            let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
            let alone = renderer.render(&scene, &|_| {}).unwrap().image;
            for y in 0..20 {
                for x in 0..24 {
                    let i = y * 24 + x;
                    let [r, g, b] = alone.rgb[i];
                    let got = px[y * 48 + 24 * k + x];
                    assert_eq!(
                        got.map(f32::to_bits),
                        [r, g, b, alone.alpha[i]].map(f32::to_bits),
                        "{view:?} ({x}, {y})"
                    );
                    lit += usize::from(r > 0.0);
                }
            }
        }
        assert!(lit > 50, "{lit} lit pixels: the views show the phantom");
        // Without the option a rerun removes the EXR.
        spec.exr = false;
        let row = run_job(&items[0], &spec, out.path(), false).row;
        assert_eq!(row.status, Status::Ok);
        assert!(!file.exists());
    }
}
