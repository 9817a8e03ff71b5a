//! The colour of a colour volume ([`ColourVolume`]): each sample's colour taken from
//! the data (trilinear in linear light), its opacity and gradient from the transfer
//! function of the volume's grey samples, as [`glint_io::Volume::colour`] describes.

use glint_core::color::srgb_to_linear;
use glint_core::RenderError;
use glint_io::Volume;

use crate::field::Loc;

/// The RGB of every voxel of a colour volume, on the grid of its
/// [`Field`](crate::Field), for a [`Classification`](crate::Classification) that
/// colours its samples from the data ([`Classification::with_colour`]).
///
/// Channels are kept as 8-bit sRGB codes (a colour image's stored values: DICOM
/// colour images are display-referred RGB, PS3.3 C.7.6.3.1.2; 16 and 32-bit channels
/// are rounded to 8 bits, below what an 8-bit PNG shows); a sample's colour is the
/// trilinear interpolation of its cell's eight voxels after each is decoded to linear
/// light (IEC 61966-2-1), the space the shader works in.
///
/// [`Classification::with_colour`]: crate::Classification::with_colour
#[derive(Clone, Debug, PartialEq)]
pub struct ColourVolume {
    dims: [usize; 3],
    /// sRGB codes per voxel, `i + dims[0] * (j + dims[1] * k)`.
    rgb: Vec<[u8; 3]>,
    /// Linear light of each 8-bit sRGB code.
    linear: [f32; 256],
}

impl ColourVolume {
    /// A colour volume of `dims` voxels from their 8-bit sRGB codes (x fastest).
    pub fn new(dims: [usize; 3], rgb: Vec<[u8; 3]>) -> Result<ColourVolume, RenderError> {
        let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if dims.iter().any(|&d| d < 2) || count != Some(rgb.len()) {
            return Err(RenderError::Parameter(format!(
                "colour volume of {dims:?} voxels (at least 2 along each axis) given {} colours",
                rgb.len()
            )));
        }
        Ok(ColourVolume {
            dims,
            rgb,
            linear: std::array::from_fn(|c| srgb_to_linear(c as f64 / 255.0) as f32),
        })
    }

    /// The colour of `volume` ([`Volume::colour`]), its channels rounded to 8 bits;
    /// `None` for a scalar volume.
    pub fn from_volume(volume: &Volume) -> Result<Option<ColourVolume>, RenderError> {
        let Some(colour) = &volume.colour else {
            return Ok(None);
        };
        let n = volume.samples.len();
        if colour.channels().iter().any(|c| c.len() != n) {
            return Err(RenderError::Parameter(format!(
                "colour channels of {:?} samples for a volume of {n}",
                colour.channels().map(|c| c.len())
            )));
        }
        let code = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        let rgb = (0..n).map(|i| colour.rgb(i).map(code)).collect();
        ColourVolume::new(volume.dims, rgb).map(Some)
    }

    /// Voxels along i, j, k.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Every voxel's 8-bit sRGB codes, `i + dims[0] * (j + dims[1] * k)` (x fastest).
    pub fn codes(&self) -> &[[u8; 3]] {
        &self.rgb
    }

    /// The linear light of each 8-bit sRGB code, as the interpolation reads it.
    pub fn linear(&self) -> &[f32; 256] {
        &self.linear
    }

    /// The 8-bit sRGB code of voxel `(i, j, k)`; `None` outside the grid.
    pub fn code(&self, i: usize, j: usize, k: usize) -> Option<[u8; 3]> {
        let [nx, ny, nz] = self.dims;
        (i < nx && j < ny && k < nz).then(|| self.rgb[i + nx * (j + ny * k)])
    }

    /// The linear RGB at a located sample: the trilinear interpolation of its cell's
    /// corners' linear colours (the field's cell: [`crate::Field`] locates every sample
    /// inside `[0, dims - 2]`, so all eight corners exist).
    #[inline(always)]
    pub(crate) fn at(&self, loc: &Loc) -> [f32; 3] {
        let [nx, ny, _] = self.dims;
        let [i, j, k] = loc.ijk;
        let t = loc.t;
        let mut out = [0.0f32; 3];
        for c in 0..8 {
            let o = [c & 1, c >> 1 & 1, c >> 2 & 1];
            let w = (if o[0] == 1 { t[0] } else { 1.0 - t[0] })
                * (if o[1] == 1 { t[1] } else { 1.0 - t[1] })
                * (if o[2] == 1 { t[2] } else { 1.0 - t[2] });
            if w == 0.0 {
                continue;
            }
            let v = self.rgb[(i + o[0]) + nx * ((j + o[1]) + ny * (k + o[2]))];
            for ch in 0..3 {
                out[ch] += w * self.linear[usize::from(v[ch])];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::{Classification, ClassifySettings, Field, FrameSettings, TransferFunction};
    use glint_core::{Image, Light, Material, RenderMode, Shader};
    use glint_io::{Rgb, Samples};
    use glint_lobe::{Geometry, LobeKind};

    const N: usize = 16;

    /// A 16^3 colour volume: a box 3..13 on every axis, pure red where i < 8 and pure
    /// blue where i >= 8, black outside; its grey samples the BT.601 luma of each
    /// (76, 29, 0) as the DICOM reader makes them.
    fn halves() -> Volume {
        let n3 = N * N * N;
        let (mut r, g, mut b) = (vec![0u8; n3], vec![0u8; n3], vec![0u8; n3]);
        let mut grey = vec![0u8; n3];
        for k in 3..13 {
            for j in 3..13 {
                for i in 3..13 {
                    let v = i + N * (j + N * k);
                    if i < 8 {
                        (r[v], grey[v]) = (255, 76);
                    } else {
                        (b[v], grey[v]) = (255, 29);
                    }
                }
            }
        }
        let mut vol = Volume::new([N; 3], [1.0; 3], Samples::U8(grey)).unwrap();
        vol.colour = Some(Rgb {
            red: Samples::U8(r),
            green: Samples::U8(g),
            blue: Samples::U8(b),
        });
        vol
    }

    /// Renders `vol` with an opaque green transfer function above luma 10, lit by a
    /// diffuse headlight (no specular white), in colour when `colour`.
    fn render(vol: &Volume, colour: bool, mode: RenderMode) -> Image {
        let field = Arc::new(Field::new(vol).unwrap());
        let tf = TransferFunction::from_flat(
            &[0.0, 0.0, 10.0, 0.0, 20.0, 1.0, 255.0, 1.0],
            &[0.0, 0.0, 1.0, 0.0],
        )
        .unwrap();
        let settings = ClassifySettings {
            mode,
            iso: 20.0,
            ..ClassifySettings::default()
        };
        let mut class = Classification::new(field, &tf, &settings).unwrap();
        if colour {
            let c = ColourVolume::from_volume(vol).unwrap().unwrap();
            class = class.with_colour(Arc::new(c)).unwrap();
        }
        let material = Material {
            ambient: 0.2,
            diffuse: 0.8,
            specular: 0.0,
            ..Material::default()
        };
        let shader = Shader::new(
            LobeKind::Exact,
            10.0,
            0,
            Geometry::Phong,
            material,
            vec![Light::HEADLIGHT],
            0.0,
        )
        .unwrap();
        let frame = FrameSettings {
            width: 48,
            height: 48,
            background: [0.0; 3],
            ..FrameSettings::default()
        };
        class
            .frame(&shader, &frame, None, crate::Transport::Local, &|_| {})
            .unwrap()
    }

    /// Pixels shown (alpha > 0.5) whose colour is within 1% of pure red, of pure blue,
    /// and the rest; panics on any pixel with green above 1% of its red and blue.
    fn hues(image: &Image) -> (usize, usize, usize) {
        let (mut red, mut blue, mut other) = (0, 0, 0);
        for (c, a) in image.rgb.iter().zip(&image.alpha) {
            assert!(c[1] <= 0.01 * (c[0] + c[2]) + 1e-6, "green in {c:?}");
            if *a <= 0.5 {
                continue;
            }
            let sum = c[0] + c[1] + c[2];
            if c[0] >= 0.99 * sum {
                red += 1;
            } else if c[2] >= 0.99 * sum {
                blue += 1;
            } else {
                other += 1;
            }
        }
        (red, blue, other)
    }

    #[test]
    fn a_colour_volume_shows_the_data_hues_shaded() {
        let vol = halves();
        for mode in [RenderMode::Composite, RenderMode::Iso] {
            let image = render(&vol, true, mode);
            let (red, blue, other) = hues(&image);
            // Two halves of one box seen from the front: hundreds of pixels each. The
            // others are where the colours meet: trilinear colour mixes them (to
            // magenta) between the voxel centres i = 7 and 8, a tenth of the box's
            // 10-voxel width (12% measured, with the perspective's side faces).
            assert!(red > 200 && blue > 200, "{mode:?}: {red} red, {blue} blue");
            let shown = red + blue + other;
            assert!(
                other * 100 < 15 * shown,
                "{mode:?}: {other} of {shown} mixed"
            );
        }
        // Without the colour, the transfer function's green.
        let grey = render(&vol, false, RenderMode::Composite);
        let green = grey
            .rgb
            .iter()
            .zip(&grey.alpha)
            .filter(|(c, a)| **a > 0.5 && c[1] > 0.1 && c[0] == 0.0 && c[2] == 0.0)
            .count();
        assert!(green > 400, "{green} green pixels");
    }

    #[test]
    fn a_colour_volume_of_another_grid_is_refused() {
        let vol = halves();
        let field = Arc::new(Field::new(&vol).unwrap());
        let tf =
            TransferFunction::from_flat(&[0.0, 0.0, 255.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
        let class = Classification::new(field, &tf, &ClassifySettings::default()).unwrap();
        let other = ColourVolume::new([N, N, N + 1], vec![[0; 3]; N * N * (N + 1)]).unwrap();
        assert!(class.with_colour(Arc::new(other)).is_err());
    }

    #[test]
    fn samples_interpolate_linear_light_between_voxels() {
        // Two voxels along i: black and white (sRGB 0 and 255), 2x2x2.
        let mut rgb = vec![[0u8; 3]; 8];
        for v in rgb.iter_mut().skip(1).step_by(2) {
            *v = [255, 128, 0];
        }
        let c = ColourVolume::new([2; 3], rgb).unwrap();
        let at = |x: f32| {
            c.at(&Loc {
                ijk: [0; 3],
                t: [x, 0.3, 0.7],
            })
        };
        assert_eq!(at(0.0), [0.0; 3]);
        let one = at(1.0);
        // sRGB 128 is linear 0.2158605 (IEC 61966-2-1).
        assert!((one[0] - 1.0).abs() < 1e-6 && (one[1] - 0.215_860_5).abs() < 1e-6);
        let half = at(0.5);
        assert!((half[0] - 0.5).abs() < 1e-6 && (half[1] - 0.107_930_3).abs() < 1e-6);
        assert_eq!(half[2], 0.0);
    }

    #[test]
    fn a_volume_gives_its_channels_in_8_bits_and_bad_sizes_are_refused() {
        let mut v = Volume::new([2; 3], [1.0; 3], Samples::U16(vec![0; 8])).unwrap();
        assert_eq!(ColourVolume::from_volume(&v).unwrap(), None);
        v.colour = Some(Rgb {
            red: Samples::U16(vec![65535; 8]),
            green: Samples::U16(vec![32896; 8]),
            blue: Samples::U16(vec![0; 8]),
        });
        let c = ColourVolume::from_volume(&v).unwrap().unwrap();
        // 32896 / 65535 * 255 = 128.0.
        assert_eq!(c.code(1, 1, 1), Some([255, 128, 0]));
        assert_eq!(c.code(2, 0, 0), None);
        v.colour.as_mut().unwrap().blue = Samples::U16(vec![0; 7]);
        assert!(ColourVolume::from_volume(&v).is_err());
        assert!(ColourVolume::new([2, 2, 1], vec![[0; 3]; 4]).is_err());
        assert!(ColourVolume::new([2; 3], vec![[0; 3]; 7]).is_err());
    }
}
