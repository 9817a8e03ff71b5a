//! Rendered images and PNG output (8- or 16-bit sRGB, written atomically).

use std::path::Path;

use crate::error::RenderError;
use crate::tf::linear_to_srgb;

/// A rendered image: linear RGB (already over the background) and the accumulated
/// opacity, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
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
    pub stats: crate::raycast::RenderStats,
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

    /// The image as an sRGB PNG file's bytes.
    pub fn encode_png(&self, depth: Depth) -> Result<Vec<u8>, png::EncodingError> {
        let mut out = Vec::new();
        let mut enc = png::Encoder::new(&mut out, self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(match depth {
            Depth::Eight => png::BitDepth::Eight,
            Depth::Sixteen => png::BitDepth::Sixteen,
        });
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&self.encode_srgb(depth))?;
        writer.finish()?;
        Ok(out)
    }

    /// Writes an sRGB PNG to `path` atomically ([`glint_io::write_atomic`]): a failure
    /// leaves no partial file.
    pub fn write_png(&self, path: &Path, depth: Depth) -> Result<(), RenderError> {
        let bytes = self.encode_png(depth).map_err(RenderError::Encode)?;
        glint_io::write_atomic(path, |w| w.write_all(&bytes)).map_err(RenderError::Write)
    }
}
