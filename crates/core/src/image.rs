//! Rendered images and PNG output (8- or 16-bit sRGB, written atomically).

use std::path::Path;

use crate::color::{linear_to_srgb, luminance};
use crate::error::RenderError;

/// A rendered image: linear RGB (already over the background) and the accumulated
/// opacity, row 0 at the top. Two images are equal when their pixels are: the work
/// counts are not compared (a lazily built field may skip a little more or less empty
/// space for the same pixels, depending on which bricks threads built first).
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB per pixel, row-major.
    pub rgb: Vec<[f32; 3]>,
    /// Accumulated opacity per pixel.
    pub alpha: Vec<f32>,
    /// Work counts of the render that made it.
    pub stats: RenderStats,
}

impl PartialEq for Image {
    fn eq(&self, other: &Image) -> bool {
        (self.width, self.height) == (other.width, other.height)
            && self.rgb == other.rgb
            && self.alpha == other.alpha
    }
}

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Work counts of one render (for tests and tuning; not timing).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderStats {
    /// Samples classified (composite mode).
    pub samples: u64,
    /// Samples with non-zero opacity, shaded and composited.
    pub shaded: u64,
    /// Macro cells leapt over.
    pub skips: u64,
}

/// PNG sample depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Depth {
    /// 8 bits per channel.
    #[default]
    Eight,
    /// 16 bits per channel.
    Sixteen,
}

impl Image {
    /// The linear RGB of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        self.rgb[(y * self.width + x) as usize]
    }

    /// sRGB-encoded samples, row-major RGB, at `depth` (16-bit samples big-endian as
    /// PNG stores them).
    pub fn encode_srgb(&self, depth: Depth) -> Vec<u8> {
        match depth {
            Depth::Eight => self
                .rgb
                .iter()
                .flat_map(|p| p.map(|c| (linear_to_srgb(c as f64) * 255.0).round() as u8))
                .collect(),
            Depth::Sixteen => self
                .rgb
                .iter()
                .flat_map(|p| p.map(|c| (linear_to_srgb(c as f64) * 65535.0).round() as u16))
                .flat_map(|v| v.to_be_bytes())
                .collect(),
        }
    }

    /// The image as an sRGB PNG file's bytes. Compressed with the png crate's `Fast`
    /// setting (fdeflate): the default level's deflate (miniz_oxide) took 7% of a
    /// one-shot MNI152 render for files about 10% smaller.
    pub fn encode_png(&self, depth: Depth) -> Result<Vec<u8>, png::EncodingError> {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(match depth {
            Depth::Eight => png::BitDepth::Eight,
            Depth::Sixteen => png::BitDepth::Sixteen,
        });
        enc.set_compression(png::Compression::Fast);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&self.encode_srgb(depth))?;
        writer.finish()?;
        Ok(out)
    }

    /// Writes an sRGB PNG ([`Image::encode_png`]) to `path` atomically
    /// ([`glint_io::write_atomic`]): a failure leaves no partial file.
    pub fn write_png(&self, path: &Path, depth: Depth) -> Result<(), RenderError> {
        let bytes = self.encode_png(depth).map_err(RenderError::Encode)?;
        Self::write_png_bytes(path, &bytes)
    }

    /// Writes PNG bytes from [`Image::encode_png`] to `path` atomically (to time
    /// encoding and writing apart).
    pub fn write_png_bytes(path: &Path, bytes: &[u8]) -> Result<(), RenderError> {
        glint_io::write_atomic(path, |out| out.write_all(bytes)).map_err(RenderError::Write)
    }
}

/// Width (sigma, pixels) of the Gaussian blur the ring measure subtracts, and how far
/// (pixels) inside the silhouette it looks: the measure glint issue 12 defines for
/// "wood-grain" slicing rings (mean absolute high-pass luminance inside the object,
/// eroded 6 px from its silhouette, with a sigma-2 px Gaussian).
pub const RING_BLUR_SIGMA: f64 = 2.0;
/// See [`RING_BLUR_SIGMA`].
pub const RING_ERODE_PX: usize = 6;
/// Accumulated opacity above which a pixel belongs to the object for the ring measure.
pub const RING_OBJECT_ALPHA: f32 = 0.5;

impl Image {
    /// Ring measure: the mean absolute difference, in 8-bit grey levels, between the
    /// image's luma (Rec. 709 weights on the 8-bit sRGB samples the PNG holds) and its
    /// Gaussian blur of [`RING_BLUR_SIGMA`] pixels, over the pixels of the object
    /// (opacity above [`RING_OBJECT_ALPHA`]) at least [`RING_ERODE_PX`] pixels inside
    /// its silhouette (a square erosion). Smooth shading gives almost 0; slicing rings,
    /// noise and fine texture raise it. `None` when no pixel is that deep inside.
    pub fn ring_measure(&self) -> Option<f64> {
        self.ring_measure_inside(RING_ERODE_PX).map(|(m, _)| m)
    }

    /// [`Image::ring_measure`] over the pixels at least `erode` pixels inside the
    /// silhouette, and how many there are: measures at growing depths tell the
    /// silhouette's own edges from what covers the object's inside.
    pub fn ring_measure_inside(&self, erode: usize) -> Option<(f64, usize)> {
        let (w, h) = (self.width as usize, self.height as usize);
        let srgb = self.encode_srgb(Depth::Eight);
        let luma: Vec<f64> = srgb
            .chunks_exact(3)
            .map(|p| luminance([p[0] as f64, p[1] as f64, p[2] as f64]))
            .collect();
        let blurred = gaussian_blur(&luma, w, h, RING_BLUR_SIGMA);
        let inside: Vec<bool> = self.alpha.iter().map(|&a| a > RING_OBJECT_ALPHA).collect();
        // Each pass erodes rows and transposes, so two give the square erosion.
        let deep = erode_rows(&erode_rows(&inside, w, h, erode), h, w, erode);
        let (mut sum, mut n) = (0.0, 0usize);
        for (i, _) in deep.iter().enumerate().filter(|(_, d)| **d) {
            sum += (luma[i] - blurred[i]).abs();
            n += 1;
        }
        (n > 0).then(|| (sum / n as f64, n))
    }
}

/// Erodes each row of a `w` x `h` mask by `r` pixels (a pixel stays when its row
/// neighbours within `r` are all set; outside the image counts as unset) and returns
/// the result transposed (`h` x `w`), so two calls erode by a square.
fn erode_rows(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for y in 0..h {
        let row = &mask[y * w..][..w];
        // Length of the run of set pixels ending at each x.
        let mut run = 0usize;
        let mut runs = vec![0usize; w];
        for (x, &m) in row.iter().enumerate() {
            run = if m { run + 1 } else { 0 };
            runs[x] = run;
        }
        for x in r..w.saturating_sub(r) {
            out[x * h + y] = runs[x + r] > 2 * r;
        }
    }
    out
}

/// Separable Gaussian blur of a `w` x `h` image, kernel cut at 3 sigma, edges clamped.
fn gaussian_blur(img: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let norm: f64 = k.iter().sum();
    let pass = |src: &[f64], w: usize, h: usize| {
        // Blurs rows and writes the result transposed.
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (o, kv) in (-r..=r).zip(&k) {
                    let xi = (x as isize + o).clamp(0, w as isize - 1) as usize;
                    s += kv * src[y * w + xi];
                }
                out[x * h + y] = s / norm;
            }
        }
        out
    };
    let t = pass(img, w, h);
    pass(&t, h, w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::srgb_to_linear;

    /// A `w` x `h` image whose pixels inside a centred disc of radius `r` are opaque
    /// grey with 8-bit sRGB level `level(x, y)`.
    fn disc(w: u32, h: u32, r: f32, level: impl Fn(u32, u32) -> u8) -> Image {
        let mut rgb = Vec::new();
        let mut alpha = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f32 - w as f32 / 2.0, y as f32 - h as f32 / 2.0);
                let inside = (dx * dx + dy * dy).sqrt() < r;
                let c = if inside {
                    srgb_to_linear(level(x, y) as f64 / 255.0) as f32
                } else {
                    0.0
                };
                rgb.push([c; 3]);
                alpha.push(if inside { 1.0 } else { 0.0 });
            }
        }
        Image {
            width: w,
            height: h,
            rgb,
            alpha,
            stats: Default::default(),
        }
    }

    #[test]
    fn ring_measure_of_flat_and_striped_discs() {
        // Flat: the blur inside the eroded disc reads only the flat level.
        let flat = disc(64, 64, 25.0, |_, _| 120);
        assert!(flat.ring_measure().unwrap() < 1e-9);
        // Columns alternating 100 and 110: a Gaussian of sigma 2 passes a period-2
        // pattern by exp(-2 pi^2 sigma^2 f^2) = exp(-19.7), so the blur is the mean
        // 105 and the measure the half-amplitude 5 (luma weights sum to 1); the kernel's
        // cut at 3 sigma leaves it a response of 7.5e-4 there, 0.004 of a grey level.
        let striped = disc(64, 64, 25.0, |x, _| if x % 2 == 0 { 100 } else { 110 });
        let m = striped.ring_measure().unwrap();
        assert!((m - 5.0).abs() < 0.01, "{m}");
        // Nothing 6 px inside a disc of radius 5.
        assert_eq!(disc(64, 64, 5.0, |_, _| 120).ring_measure(), None);
    }

    #[test]
    fn png_bytes_decode_to_the_srgb_samples() {
        let img = disc(16, 8, 5.0, |x, y| (x * 13 + y * 7) as u8);
        let bytes = img.encode_png(Depth::Eight).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (16, 8));
        assert_eq!(
            &buf[..info.buffer_size()],
            &img.encode_srgb(Depth::Eight)[..]
        );
    }
}
